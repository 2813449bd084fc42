"""The paper's Table II (Tao et al.), quoted: the numbers the report sets ours beside."""

# case: (human-involved episodes, total episodes, total error, human effort), one person each
PAPER_TABLE2 = {1: (18, 25, 1.61, 0.0075), 2: (6, 31, 0.82, 0.0020), 3: (19, 19, 2.04, 0.0078),
                4: (14, 14, 1.14, 0.0021), 5: (24, 24, 6.26, 0.0096), 6: (16, 16, 1.24, 0.0023)}
PAPER_EPISODE_SECONDS = 40.0        # the paper's episodes (and ours by default): 40 s
TARGET_PERSON_TIME_RATIO = 2.0      # the study's target: the person's time within 2x the paper's


def paper_person_minutes(case_id: int) -> float:
    """Return the paper's person time in a case (its human-involved episodes x 40 s), min."""
    return PAPER_TABLE2[case_id][0] * PAPER_EPISODE_SECONDS / 60.0
