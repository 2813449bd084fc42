"""docs/results.md and docs/ppo/results.md say what their sessions.csv holds (recomputable).

Numbers of each page recomputed from the per-session CSV written with it, for the primary
profile: each case's mean human-involved and total episodes (Table II), its mean unit-free
error and its chattering robots (Table II), converged sessions (the convergence table), the
person's median minutes (the person's-time table) and the mean counts the paper's way
(training episodes only; cases 7 and 8 with their pre-training episodes).
"""

import csv
import pathlib
import re
import statistics

import pytest

DOCS = pathlib.Path(__file__).resolve().parents[1] / 'docs'
PAGES = [DOCS, DOCS / 'ppo']     # the default configuration's page, then PPO's


def table2_cells(text: str, case_id: int, seeds: int) -> list:
    """Return the cells of a case's Table II row (the first table whose row starts so)."""
    match = re.search(rf'^\| {case_id} \| [^|]+ \| [^|]+ \| {seeds} \| .*$', text, re.MULTILINE)
    assert match, f'no Table II row for case {case_id}'
    return [cell.strip() for cell in match.group(0).strip('|').split('|')]


def leading_number(cell: str) -> float:
    return float(cell.split()[0])


@pytest.mark.parametrize('folder', PAGES, ids=['default', 'ppo'])
def test_the_tables_of_the_results_page_recompute_from_its_csv(folder):
    text = (folder / 'results.md').read_text()
    rows = list(csv.DictReader((folder / 'results' / 'sessions.csv').open()))
    primary = 'paper'
    cases = sorted({int(row['case_id']) for row in rows if row['profile'] == primary})
    assert cases, 'no sessions of the primary profile in the CSV'
    for case_id in cases:
        mine = [row for row in rows
                if row['profile'] == primary and int(row['case_id']) == case_id]
        cells = table2_cells(text, case_id, len(mine))
        mean = lambda key: statistics.mean(float(row[key]) for row in mine)  # noqa: E731
        assert leading_number(cells[4]) == round(mean('human_involved_episodes'), 1)
        assert leading_number(cells[5]) == round(mean('total_episodes'), 1)
        assert leading_number(cells[11]) == round(mean('tolerance_error'), 2), cells[11]
        chatter = sum(row['robot_chatters'] == 'True' for row in mine)
        assert cells[-1] == f'{chatter} / {len(mine)}', cells[-1]
        converged = sum(row['converged'] == 'True' for row in mine)
        assert f'| {case_id} | {converged}/{len(mine)} |' in text
        minutes = statistics.median(float(row['person_minutes']) for row in mine)
        assert re.search(rf'^\| {case_id} \| {len(mine)} \| {minutes:.1f} \[', text,
                         re.MULTILINE), (case_id, minutes)
        paper_way = re.search(rf'^\| {case_id} \| [\d.]+ \[[^]]*\] / [\d.]+ \[[^]]*\] \| '
                              rf'([\d.]+) \[[^]]*\] / ([\d.]+) ', text, re.MULTILINE)
        assert paper_way, f"no row counted the paper's way for case {case_id}"
        assert float(paper_way.group(1)) == round(mean('paper_person_episodes'), 1)
        assert float(paper_way.group(2)) == round(mean('paper_episodes'), 1)
