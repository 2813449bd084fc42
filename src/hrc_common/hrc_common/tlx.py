"""The raw NASA-TLX (pure): six subscales scored 0..100, unweighted mean.

Hart, S. G. (2006). NASA-Task Load Index (NASA-TLX); 20 years later. Proc. HFES 50, 904-908:
the "raw TLX" drops the pairwise weighting and averages the six subscale ratings. The page
offers 0..100 in steps of 5 (the paper form's 21 marks); performance runs from 0 = perfect to
100 = failure, as on the original form.
"""

TLX_SCALES = ('mental', 'physical', 'temporal', 'performance', 'effort', 'frustration')
# The form's grid: 0, 5, ..., 100 (the paper form's 21 marks).
TLX_STEP = 5
# Fields of a posted answer besides the scales: the condition the page asked about, and
# whether the answer knowingly replaces an earlier one of the same condition.
ANSWER_FIELDS = ('condition', 'correction')


def check_tlx(answer, step: float = None) -> tuple:
    """Return ({scale: score}, reasons): every reason why ``answer`` is not a full raw TLX.

    ``step``: the values must lie on the grid 0, step, ..., 100 (the page's form: ``TLX_STEP``);
    None accepts any number in 0..100 (answers stored before the grid was enforced).
    """
    if not isinstance(answer, dict):
        return {}, ['the answer must be a mapping of the six scales']
    scores, reasons = {}, []
    for scale in TLX_SCALES:
        value = answer.get(scale)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            reasons.append(f'{scale}: missing or not a number ({value!r})')
        elif not 0 <= value <= 100:
            reasons.append(f'{scale}: {value} is outside 0..100')
        elif step and abs(value / step - round(value / step)) > 1e-9:
            reasons.append(f"{scale}: {value} is not on the form's grid (0, {step:g}, ..., "
                           f'100)')
        else:
            scores[scale] = float(value)
    extra = sorted(set(answer) - set(TLX_SCALES) - set(ANSWER_FIELDS))
    if extra:
        reasons.append(f'unknown fields {extra}')
    return scores, reasons


def raw_tlx(scores: dict) -> float:
    """Return the raw TLX: the unweighted mean of the six subscales (0..100)."""
    return sum(scores[scale] for scale in TLX_SCALES) / len(TLX_SCALES)
