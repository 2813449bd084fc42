"""The study folder's session index: its file and entry format (pure, no rclpy).

Written by the session runner (``hrc_live.study.append_index``, one entry per session a subject
took part in) and read by the report by subject (``hrc_bag.report.study``): a contract between
two packages, so it lives here (hrc_bag sits below hrc_live). The rest of the study protocol
(registry, case orders) is ``hrc_live.study``; the NASA-TLX scales are ``hrc_common.tlx``.
"""

from dataclasses import dataclass

from hrc_common.cases import paper_case_ids

INDEX_FILE = 'index.yaml'
SESSION_KINDS = ('practice', 'condition')


def __getattr__(name):
    """Return ``PAPER_CASES``: the paper's cases of params/cases.yaml (``paper_case_ids``).

    Read when first asked for (not at import: a broken cases file is reported by whoever needs
    the cases, with its reasons), never a copy of the case table.
    """
    if name == 'PAPER_CASES':
        return paper_case_ids()
    raise AttributeError(f'module {__name__!r} has no attribute {name!r}')


@dataclass
class IndexEntry:
    """One session a subject took part in."""

    subject_id: str
    session_id: str
    case: int
    kind: str                   # practice | condition
    position: int               # 1-based position of the case in the subject's order (0 = ?)
    started: str                # ISO date-time
    ended: str
    exit_code: int
    bags: str                   # folder of the session's bags
    run_dir: str                # logs, parameters, checkpoints, report
    tlx_file: str = ''          # raw NASA-TLX answers ('' = none asked)
