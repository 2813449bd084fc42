"""The display node in its own process over DDS, its pages in a real headless Chromium.

The test plays the agent (its topics, its parameters and its operator services) and runs a real
sim node with a non-default pendulum length that is never reset: it only answers the display's
parameter query, so the page must draw with the sim's geometry, not the defaults. Screenshots
at known states are checked for the bodies' colours where the state puts them, at full HD and
at a phone's size, including the extreme configurations (beam at a hinge stop, ball at an end
stop, slider at an end of the rod).
"""

import json
import math
import os
import pathlib
import functools
import http.client
import http.server
import re
import socket
import sys
import threading
import time
import urllib.error
import urllib.request

from hrc_common import qos
from hrc_common.contract import BODY_COLOURS, rgb8
from hrc_testing.nodes import wait_for
from hrc_live.display_documents import COLORS
from hrc_live.input_check import INPUT_LOST_TOPIC
from hrc_msgs.msg import HumanAction, SessionStatus
from hrc_sim_node.body_geometry import body_poses
from hrc_sim_node.physics import PhysicsState
import pytest
import yaml

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from browser import screenshot, set_viewport  # noqa: E402
from page_graph import (close_to, fetch, PENDULUM_LENGTH, PHYSICS,  # noqa: E402
                        session_status, status, task_state)

BALL, PENDULUM, SLIDER, ROD = (rgb8(BODY_COLOURS[name]) for name in
                               ('ball', 'pendulum', 'slider', 'rod'))


def test_a_port_in_use_is_refused_with_the_reason(start_node):
    with socket.socket() as taken:
        taken.bind(('127.0.0.1', 0))
        taken.listen()
        port = taken.getsockname()[1]
        display = start_node('hrc_live', 'display_node', parameters={'port': port})
        assert display.wait(timeout=60) == 2
    assert f'cannot serve on 127.0.0.1:{port}' in display.output


def show(agent, browser, episode, step, slider, angle, ball):
    """Publish a state until the page has drawn it, then let the smoothing settle."""
    def drawn():
        agent.state.publish(task_state(episode, step, slider, angle, ball))
        stats = browser.execute_script('return window.hrcStats(1)')
        return stats['lastDrawnStep'] == step and stats['lastDrawnEpisode'] == episode
    assert wait_for(drawn, 30, 0.2)
    time.sleep(0.4)  # the correction towards a new state decays in ~60 ms


def page_pixel(browser, image, y, z):
    column, row = browser.execute_script(f'return window.hrcPagePixel({y}, {z})')
    return (int(round(column)), int(round(row))), image.getpixel((int(round(column)),
                                                                  int(round(row))))


def check_bodies(browser, image, slider, angle, ball, where):
    """Assert the ball, beam, slider and rod are drawn where the state puts them."""
    state = PhysicsState(0, 0.0, slider, 0.0, angle, 0.0, ball, 0.0, 0.0, 0.0, False, False)
    poses = body_poses(state, PHYSICS)
    width, height = image.size
    for name, (y, z), colour in (
            ('ball', (poses['ball'][0][1], poses['ball'][0][2]), BALL),
            ('beam', (0.3 * PENDULUM_LENGTH * math.cos(angle),
                      slider + 0.3 * PENDULUM_LENGTH * math.sin(angle)), PENDULUM),
            ('beam end', (0.97 * PENDULUM_LENGTH * math.cos(angle),
                          slider + 0.97 * PENDULUM_LENGTH * math.sin(angle)), PENDULUM),
            ('slider', (-0.018, slider), SLIDER)):
        ball_y, ball_z = poses['ball'][0][1], poses['ball'][0][2]
        if name != 'ball' and math.hypot(y - ball_y, z - ball_z) < 1.5 * PHYSICS.ball_radius:
            continue  # the ball is drawn over this point
        (column, row), pixel = page_pixel(browser, image, y, z)
        assert 0 <= column < width and 0 <= row < height, (where, name, column, row)
        assert close_to(pixel, colour), (where, name, pixel, colour)


def test_the_page_draws_the_state_at_full_hd_and_phone_size(graph, tmp_path):
    agent, port, browser, display = graph
    browser.get(f'http://127.0.0.1:{port}/')
    assert wait_for(lambda: browser.execute_script(
        'return window.hrcScene.geometry && window.hrcScene.geometry.pendulum_length') ==
        PENDULUM_LENGTH, 30, 0.2)
    saved = pathlib.Path(os.environ.get('HRC_SCREENSHOTS', tmp_path))
    slider, angle, ball = 0.05, 0.2, 0.12
    show(agent, browser, 3, 7, slider, angle, ball)
    image = screenshot(browser)
    image.save(saved / 'page-1920x1080.png')
    check_bodies(browser, image, slider, angle, ball, 'full HD')
    # With the default 0.5 m beam its end would be here; with the sim's 0.4 m it is background.
    _, pixel = page_pixel(browser, image, 0.47 * math.cos(angle), slider + 0.47 * math.sin(angle))
    assert close_to(pixel, COLORS['background']), pixel
    banner = browser.find_element('id', 'banner')
    assert banner.text == ('Your turn: keep the slider in the middle of the rod and keep the '
                           'ball in the middle of the pendulum')
    assert browser.find_element('id', 'label').text == 'Round 4 of at most 30'
    # The reachable extremes stay in the picture, at full HD and at a phone's size.
    limit = PHYSICS.pendulum_limit
    extremes = [(0.1, limit, PENDULUM_LENGTH / 2), (-0.1, -limit, -PENDULUM_LENGTH / 2),
                (0.1, -limit, PENDULUM_LENGTH / 2), (-0.1, limit, -PENDULUM_LENGTH / 2)]
    for size in ((1920, 1080), (390, 844)):
        set_viewport(browser, *size)
        for step, (slider, angle, ball) in enumerate(extremes, start=8 + 10 * (size[0] < 1000)):
            show(agent, browser, 3, step, slider, angle, ball)
            image = screenshot(browser)
            assert image.size == size
            check_bodies(browser, image, slider, angle, ball, f'{size} {slider, angle, ball}')
        image.save(saved / f'page-{size[0]}x{size[1]}-extreme.png')
        box = browser.find_element('id', 'banner').rect
        assert box['y'] >= 0 and box['y'] + box['height'] <= size[1]
        panel = browser.find_element('id', 'label').rect
        assert 0 <= panel['y'] and panel['y'] + panel['height'] <= size[1], panel

    # A non-finite state: a clear notice on the page, status.json still answers.
    agent.state.publish(task_state(3, 30, float('nan'), 0.0, 0.0))
    notice = browser.find_element('id', 'notice')
    assert wait_for(lambda: notice.is_displayed(), 20, 0.2)
    assert 'invalid state' in notice.text
    code, body = fetch(port, '/status.json')
    assert code == 200 and json.loads(body)['invalid_state'] is True
    agent.state.publish(task_state(3, 31, 0.0, 0.0, 0.0))
    assert wait_for(lambda: not notice.is_displayed(), 20, 0.2)

    # At the human's rate the picture follows the states within a period too (slice > 0),
    # while the session's own view (status.json: counters, errors) keeps the period's state.
    within = task_state(3, 32, 0.04, -0.1, 0.05)
    within.slice = 4

    def drawn_within():
        agent.slice_state.publish(within)
        return browser.execute_script('return window.hrcStats(1)')['lastDrawnStep'] == 32
    assert wait_for(drawn_within, 30, 0.2)
    assert json.loads(fetch(port, '/status.json')[1])['state']['step'] == 31


def test_console_input_health_and_buttons_then_the_tlx_form_on_the_page(graph, tmp_path):
    agent, port, browser, display = graph
    browser.get(f'http://127.0.0.1:{port}/console')
    action = HumanAction(source=HumanAction.SOURCE_SIMULATED, source_detail='profile default',
                         engaged=True, command=0.1)

    def showing_source():
        agent.human.publish(action)
        agent.state.publish(task_state(3, 5, 0.02, 0.1, 0.05))
        return 'simulated (profile default)' in browser.find_element('id', 'input').text
    assert wait_for(showing_source, 30, 0.2), browser.find_element('tag name', 'body').text
    assert 'case 2' in browser.find_element('id', 'title').text
    # every node's health from /diagnostics, in its level's colour
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
    health = agent.node.create_publisher(DiagnosticArray, '/diagnostics', 10)

    def showing_health():
        health.publish(DiagnosticArray(status=[DiagnosticStatus(
            name='agent: learner', level=DiagnosticStatus.ERROR, message='update failed')]))
        return 'ERROR: update failed' in browser.find_element('id', 'health').text
    assert wait_for(showing_health, 30, 0.2), browser.find_element('id', 'health').text
    cell = browser.find_element('css selector', '#health td.bad')
    assert cell.text == 'ERROR: update failed'
    browser.find_element('id', 'pause').click()
    answer = browser.find_element('id', 'answer')
    assert wait_for(lambda: 'pause requested (test agent)' in answer.text, 30, 0.2), answer.text
    assert agent.calls == ['pause']
    # The input goes quiet: the command's age grows and it is no longer healthy.
    assert wait_for(lambda: float(status(port)['console']['input']['age_s']) > 1.0, 60, 0.2)
    assert status(port)['console']['input']['healthy'] is False
    # The session runner says the joystick is gone: both pages say so.
    from std_msgs.msg import String
    lost = agent.node.create_publisher(String, INPUT_LOST_TOPIC, qos.SESSION_QOS)
    lost.publish(String(data='/dev/input/js0 unplugged'))
    assert wait_for(lambda: 'joystick disconnected' in browser.find_element(
        'id', 'input').text, 20, 0.2)
    assert status(port)['banner'].startswith('The joystick is disconnected')
    lost.publish(String(data=''))

    # Mid-session the questionnaire is not asked and not accepted (even from the own page).
    code, text = post(port, '/tlx', json.dumps({**ANSWER, 'condition': 'display-test'}),
                      page_token(port))
    assert code == 409 and 'at the end of the condition' in text, (code, text)

    # After the condition the person's page asks the raw NASA-TLX; it is stored 0600.
    browser.get(f'http://127.0.0.1:{port}/')
    agent.session.publish(session_status(phase=SessionStatus.PHASE_DONE))
    form = browser.find_element('id', 'tlx')
    assert wait_for(lambda: form.is_displayed(), 30, 0.2)
    assert 'the part you played' in form.text
    send = browser.find_element('id', 'tlx-send')
    # Nothing is pre-set: no mark ticked, Send stays disabled until every scale is ticked.
    assert browser.execute_script(
        "return document.querySelectorAll('#tlx input:checked').length") == 0
    assert not send.is_enabled()
    answer = {'mental': 40, 'physical': 10, 'temporal': 30, 'performance': 20,
              'effort': 80, 'frustration': 15}
    for scale, value in answer.items():
        assert not send.is_enabled(), scale
        browser.find_element('css selector', f'input[name="{scale}"][value="{value}"]').click()
    assert wait_for(send.is_enabled, 30, 0.1)
    send.click()
    assert wait_for(lambda: not form.is_displayed(), 20, 0.2)
    banner = browser.find_element('id', 'banner')
    assert wait_for(lambda: banner.text == 'Thank you, your answers are saved', 20, 0.2), \
        banner.text
    stored = tmp_path / 'tlx.yaml'
    records = yaml.safe_load(stored.read_text())
    assert len(records) == 1 and records[0]['session_id'] == 'display-test'
    assert records[0]['scales'] == {scale: float(value) for scale, value in answer.items()}
    assert records[0]['raw_tlx'] == pytest.approx(sum(answer.values()) / 6, abs=0.01)
    assert stored.stat().st_mode & 0o777 == 0o600

    # The server checks on its own: off the grid, another condition, a second answer.
    token = page_token(port)
    code, text = post(port, '/tlx', json.dumps({**ANSWER, 'mental': 7.3,
                                                'condition': 'display-test'}), token)
    assert code == 400 and "not on the form's grid" in text, text
    code, text = post(port, '/tlx', json.dumps({**ANSWER, 'condition': 'other'}), token)
    assert code == 409 and "asked about 'display-test'" in text, text
    code, text = post(port, '/tlx', json.dumps({**ANSWER, 'condition': 'display-test'}), token)
    assert code == 409 and 'must be sent as a correction' in text, text
    assert len(yaml.safe_load(stored.read_text())) == 1
    code, text = post(port, '/tlx', json.dumps({**ANSWER, 'condition': 'display-test',
                                                'correction': True}), token)
    assert code == 200, text
    records = yaml.safe_load(stored.read_text())
    assert [record.get('correction', False) for record in records] == [False, True]
    assert records[1]['corrects'] == records[0]['answered']

    # The session closes behind the person's page: it keeps thanking them (it said
    # "Connection to the session lost: retrying" in red). The lost stream is an event the page
    # sees (EventSource readyState leaves OPEN), waited on, not a time.
    display.stop()
    assert wait_for(lambda: fetch_fails(port), 30, 0.2)
    # the page's stream leaves OPEN (1) when its error handler has run
    assert wait_for(lambda: browser.execute_script('return window.hrcEvents.readyState') != 1,
                    30, 0.2)
    assert banner.text == 'Thank you, your answers are saved'
    assert 'lost' not in browser.find_element('id', 'page').text


ANSWER = {'mental': 40, 'physical': 10, 'temporal': 30, 'performance': 20, 'effort': 50,
          'frustration': 15}


def fetch_fails(port) -> bool:
    """Return whether the display no longer answers on ``port``."""
    try:
        fetch(port, '/status.json')
    except OSError:
        return True
    return False


def page_token(port) -> str:
    """Return the session secret the served page holds (as the page's script reads it)."""
    page = fetch(port, '/')[1].decode()
    return re.search(r'<meta name="hrc-token" content="([^"]+)">', page).group(1)


def post(port, path, body='', token=None, origin=None, host=None):
    """POST as the own page would (Origin, secret); return (code, text) even for errors."""
    connection = http.client.HTTPConnection('127.0.0.1', port, timeout=10)
    headers = {'Origin': origin or f'http://127.0.0.1:{port}'}
    if token is not None:
        headers['X-HRC-Token'] = token
    if host is not None:
        headers['Host'] = host
    connection.request('POST', path, body=body.encode(), headers=headers)
    reply = connection.getresponse()
    answer = reply.status, reply.read().decode()
    connection.close()
    return answer


def raw_request(port, data: bytes) -> bytes:
    """Send raw bytes; return everything the server answers before it closes."""
    with socket.create_connection(('127.0.0.1', port), timeout=10) as connection:
        connection.sendall(data)
        connection.shutdown(socket.SHUT_WR)
        chunks = []
        while True:
            chunk = connection.recv(65536)
            if not chunk:
                return b''.join(chunks)
            chunks.append(chunk)


FOREIGN_PAGE = """<!DOCTYPE html><html><body>
<iframe name="sink" style="display:none"></iframe>
<form id="tlx" method="POST" action="TARGET/tlx" enctype="text/plain" target="sink">
<input name='{"mental":50,"physical":50,"temporal":50,"performance":50,"effort":50,
"frustration":50,"condition":"display-test","x":"' value='"}'>
</form>
<script>
const target = 'TARGET', results = {};
async function attempt(name, path, options) {
  try {
    const reply = await fetch(target + path, options);
    results[name] = reply.type + ' ' + reply.status;
  }
  catch (error) { results[name] = 'failed: ' + error; }
}
const tlx = JSON.stringify({mental: 50, physical: 50, temporal: 50, performance: 50, effort: 50,
                            frustration: 50, condition: 'display-test'});
(async () => {
  for (const command of ['pause', 'resume', 'abort']) {
    // A "simple" request: no preflight, the browser sends it (only the answer is hidden).
    await attempt(command + ' no-cors', '/control/' + command, {method: 'POST', mode: 'no-cors'});
    await attempt(command + ' text/plain', '/control/' + command,
                  {method: 'POST', mode: 'no-cors', headers: {'Content-Type': 'text/plain'}});
    // With a guessed secret: the header forces a preflight the server does not grant.
    await attempt(command + ' guessed secret', '/control/' + command,
                  {method: 'POST', headers: {'X-HRC-Token': 'guess'}});
    navigator.sendBeacon(target + '/control/' + command, 'x');
  }
  await attempt('tlx no-cors', '/tlx', {method: 'POST', mode: 'no-cors', body: tlx,
                                        headers: {'Content-Type': 'text/plain'}});
  navigator.sendBeacon(target + '/tlx', tlx);
  await attempt('read the page (for its secret)', '/', {});
  await attempt('read status', '/status.json', {});
  document.getElementById('tlx').submit();
  await new Promise((done) => setTimeout(done, 1500));
  window.foreignDone = results;
})();
</script></body></html>"""


def test_a_foreign_page_in_the_browser_changes_nothing(graph, tmp_path):
    """A page of another origin tries every control and the TLX form: every try is refused."""
    agent, port, browser, display = graph
    agent.session.publish(session_status(phase=SessionStatus.PHASE_DONE))  # the TLX is asked
    assert wait_for(lambda: status(port)['session']['phase'] == 'done', 20, 0.2)
    site = tmp_path / 'site'
    site.mkdir()
    (site / 'evil.html').write_text(FOREIGN_PAGE.replace('TARGET', f'http://127.0.0.1:{port}'))
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(site))
    foreign = http.server.ThreadingHTTPServer(('127.0.0.1', 0), handler)
    threading.Thread(target=foreign.serve_forever, daemon=True).start()
    try:
        browser.get(f'http://127.0.0.1:{foreign.server_address[1]}/evil.html')
        assert wait_for(lambda: browser.execute_script('return window.foreignDone'), 30, 0.2)
        results = browser.execute_script('return window.foreignDone')
    finally:
        foreign.shutdown()
        foreign.server_close()
    # Reading the page or the status across origins fails (no CORS grant): no secret leaks.
    assert results['read the page (for its secret)'].startswith('failed'), results
    assert results['read status'].startswith('failed'), results
    assert results['pause guessed secret'].startswith('failed'), results
    time.sleep(1.0)  # let a request that got through reach the agent
    assert agent.calls == [], (agent.calls, results)
    assert not (tmp_path / 'tlx.yaml').exists()
    # The requests did arrive and were refused, each logged with its reason.
    def refusals():
        return re.findall(r"refused POST (/\S+) from 127\.0\.0\.1: foreign Origin "
                          r"'http://127\.0\.0\.1:\d+'", display.output)
    assert wait_for(lambda: len(refusals()) >= 3 * 2 + 2, 60, 0.2), display.output
    assert {'/control/pause', '/control/resume', '/control/abort', '/tlx'} <= set(refusals())
    # The own page still acts (its secret, its origin).
    code, text = post(port, '/control/pause', token=page_token(port))
    assert code == 200 and agent.calls == ['pause'], (code, text)


def test_a_rebinding_host_reads_nothing_and_malformed_requests_get_400(graph):
    agent, port, browser, display = graph
    # A DNS-rebinding site: its name resolves to 127.0.0.1, the browser sends its Host.
    for path in ('/status.json', '/', '/console', '/events'):
        request = urllib.request.Request(f'http://127.0.0.1:{port}{path}',
                                         headers={'Host': f'rebind.example:{port}'})
        with pytest.raises(urllib.error.HTTPError) as refused:
            urllib.request.urlopen(request, timeout=10)
        assert refused.value.code == 403, path
        assert b'foreign Host' in refused.value.read()
    code, _ = post(port, '/control/pause', token=page_token(port), host=f'rebind.example:{port}',
                   origin=f'http://rebind.example:{port}')
    assert code == 403 and agent.calls == []
    # The own origin without the secret (a local tool forging Origin): refused too.
    code, text = post(port, '/control/abort')
    assert code == 403 and 'X-HRC-Token' in text and agent.calls == []
    assert 'refused GET /status.json from 127.0.0.1: foreign Host' in display.output
    # Malformed: a negative, a non-numeric and a huge Content-Length.
    for length, expected in ((b'-5', b'400'), (b'abc', b'400'), (b'99999999', b'413')):
        answer = raw_request(port, b'POST /control/pause HTTP/1.1\r\nHost: 127.0.0.1\r\n'
                             b'Content-Length: ' + length + b'\r\n\r\nxx')
        assert answer.startswith(b'HTTP/1.1 ' + expected), (length, answer[:200])
    assert b'400 - Bad request syntax' in raw_request(port, b'GARBAGE\r\n\r\n')
    assert status(port)['session'] is not None     # the server still answers
    assert agent.calls == []
    assert 'Traceback' not in display.output
