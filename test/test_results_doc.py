"""docs/results.md says what docs/results/sessions.csv holds (one run, recomputable).

A few numbers of the page recomputed from the per-session CSV written with it: each case's mean
human-involved and total episodes (Table II), converged sessions (the convergence table) and the
person's median minutes (the person's-time table), for the primary profile.
"""

import csv
import pathlib
import re
import statistics

DOCS = pathlib.Path(__file__).resolve().parents[1] / 'docs'


def test_the_tables_of_results_md_recompute_from_its_csv():
    text = (DOCS / 'results.md').read_text()
    rows = list(csv.DictReader((DOCS / 'results' / 'sessions.csv').open()))
    primary = 'paper'
    cases = sorted({int(row['case_id']) for row in rows if row['profile'] == primary})
    assert cases, 'no sessions of the primary profile in the CSV'
    for case_id in cases:
        mine = [row for row in rows
                if row['profile'] == primary and int(row['case_id']) == case_id]
        human = statistics.mean(float(row['human_involved_episodes']) for row in mine)
        total = statistics.mean(float(row['total_episodes']) for row in mine)
        table2 = re.search(rf'^\| {case_id} \| [^|]+ \| [^|]+ \| {len(mine)} \| '
                           rf'([\d.]+) \[[^]]*\] \| ([\d.]+) \[', text, re.MULTILINE)
        assert table2, f'no Table II row for case {case_id}'
        assert float(table2.group(1)) == round(human, 1)
        assert float(table2.group(2)) == round(total, 1)
        converged = sum(row['converged'] == 'True' for row in mine)
        assert f'| {case_id} | {converged}/{len(mine)} |' in text
        minutes = statistics.median(float(row['person_minutes']) for row in mine)
        assert re.search(rf'^\| {case_id} \| {len(mine)} \| {minutes:.1f} \[', text,
                         re.MULTILINE), (case_id, minutes)
