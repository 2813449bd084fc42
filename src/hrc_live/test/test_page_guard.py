"""Who may act on the display (pure): the Host, Origin and secret checks, and the TLX's grid."""

from hrc_live.page_server import host_name, RequestGuard, TOKEN_HEADER
from hrc_common.tlx import check_tlx, TLX_STEP

PORT, TOKEN = 8765, 'session-secret'
ANSWER = {'mental': 40, 'physical': 10, 'temporal': 30, 'performance': 20, 'effort': 50,
          'frustration': 15}


def guard():
    return RequestGuard('127.0.0.1', PORT, TOKEN)


def own_post(**changes):
    headers = {'Host': f'127.0.0.1:{PORT}', 'Origin': f'http://127.0.0.1:{PORT}',
               TOKEN_HEADER: TOKEN}
    headers.update(changes)
    return {name: value for name, value in headers.items() if value is not None}


def test_host_names_lose_their_port_and_case():
    assert host_name('LocalHost:8765') == 'localhost'
    assert host_name('[::1]:8765') == '[::1]'
    assert host_name('127.0.0.1') == '127.0.0.1'
    assert host_name('evil.example:8765') == 'evil.example'


def test_reads_need_a_loopback_host_only():
    for host in ('127.0.0.1:8765', 'localhost:8765', '[::1]:8765', 'localhost'):
        assert guard().refusal('GET', {'Host': host}) == '', host
    # A DNS-rebinding site resolves its own name to 127.0.0.1: its Host still names it.
    assert 'foreign Host' in guard().refusal('GET', {'Host': 'evil.example:8765'})
    assert guard().refusal('GET', {}) == 'no Host header'


def test_the_own_page_may_act():
    assert guard().refusal('POST', own_post()) == ''
    assert guard().refusal('POST', own_post(Host=f'localhost:{PORT}',
                                            Origin=f'http://localhost:{PORT}')) == ''


def test_a_foreign_origin_a_missing_origin_or_a_wrong_secret_is_refused():
    assert 'foreign Origin' in guard().refusal('POST', own_post(Origin='http://evil.example'))
    # Another port of the same machine is another origin (another local web page).
    assert 'foreign Origin' in guard().refusal('POST', own_post(Origin='http://127.0.0.1:9'))
    assert 'no Origin' in guard().refusal('POST', own_post(Origin=None))
    assert TOKEN_HEADER in guard().refusal('POST', own_post(**{TOKEN_HEADER: None}))
    assert TOKEN_HEADER in guard().refusal('POST', own_post(**{TOKEN_HEADER: 'guess'}))
    assert 'foreign Host' in guard().refusal('POST', own_post(Host='evil.example'))


def test_tlx_values_must_lie_on_the_forms_grid():
    assert TLX_STEP == 5
    scores, reasons = check_tlx(ANSWER, step=TLX_STEP)
    assert reasons == [] and scores['effort'] == 50.0
    _, reasons = check_tlx({**ANSWER, 'mental': 7.3}, step=TLX_STEP)
    assert reasons == ["mental: 7.3 is not on the form's grid (0, 5, ..., 100)"]
    # Every reason at once: off grid, missing, outside the scale.
    _, reasons = check_tlx({**ANSWER, 'mental': 7.3, 'effort': None, 'temporal': 105},
                           step=TLX_STEP)
    assert len(reasons) == 3, reasons
    # Stored answers are read without the grid (older files): 7.3 is still a number in 0..100.
    assert check_tlx({**ANSWER, 'mental': 7.3})[1] == []
    assert check_tlx({**ANSWER, 'correction': True, 'condition': 'c'}, step=TLX_STEP)[1] == []
