"""The display node in its own process over DDS: a headless "screenshot" fetched over HTTP.

The test plays the agent (its topics and its parameters) and runs a real sim node with a
non-default pendulum length that is never reset: it only answers the display's parameter query,
so the frame must be drawn with the sim's geometry, not the defaults.
"""

from dataclasses import fields
import io
import json
import math
import pathlib
import re
import socket
import urllib.request

from hrc_common import qos, topics
from hrc_common.params import as_dict, load_yaml
from hrc_common.testing import wait_for
from hrc_live.display_core import (BACKGROUND_COLOR, BALL_COLOR, layout, PENDULUM_COLOR,
                                   ROD_COLOR, SLIDER_COLOR)
from hrc_live.display_node import DisplayParams
from hrc_msgs.msg import EpisodeSummary, SessionStatus, TaskState
from hrc_sim_node.physics import body_poses, PhysicsParams, PhysicsState
from PIL import Image
import yaml

PARAMS_FILE = pathlib.Path(__file__).resolve().parents[3] / 'params' / 'display.yaml'
PENDULUM_LENGTH = 0.4  # not the default 0.5: the display must take it from the sim


def test_params_yaml_mirrors_the_dataclass_defaults():
    assert as_dict(load_yaml(DisplayParams, PARAMS_FILE, 'display')) == as_dict(DisplayParams())
    document = yaml.safe_load(PARAMS_FILE.read_text())
    assert set(document['display']['ros__parameters']) == {f.name for f in fields(DisplayParams)}


def test_a_port_in_use_is_refused_with_the_reason(start_node):
    with socket.socket() as taken:
        taken.bind(('127.0.0.1', 0))
        taken.listen()
        port = taken.getsockname()[1]
        display = start_node('hrc_live', 'display_node', parameters={'port': port})
        assert display.wait(timeout=60) == 2
    assert f'cannot serve on 127.0.0.1:{port}' in display.output


def served_port(process) -> int:
    found = []

    def logged():
        match = re.search(r'serving the display on http://127\.0\.0\.1:(\d+)/', process.output)
        if match:
            found.append(int(match.group(1)))
        return bool(found)

    assert wait_for(logged, timeout=60), process.output
    return found[0]


def fetch(port, path):
    with urllib.request.urlopen(f'http://127.0.0.1:{port}{path}', timeout=10) as answer:
        return answer.headers.get('Content-Type'), answer.read()


def status(port) -> dict:
    return json.loads(fetch(port, '/status.json')[1])


def task_state(episode, step, slider, angle, ball, final=False):
    message = TaskState(episode=episode, step=step, slider_position=slider, pendulum_angle=angle,
                        ball_position=ball, truncated=final)
    message.header.stamp.sec = step
    return message


def session_status(**values):
    message = SessionStatus(session_id='display-test', case_id=2,
                            strategy='responsibility_guided', training_step=1,
                            training_step_count=2, robot_dof=SessionStatus.DOF_ROTATION,
                            human_dof=SessionStatus.DOF_TRANSLATION, human_involved=True,
                            human_subtasks=['slider', 'ball'], episode=3, total_episodes=3,
                            human_involved_episodes=1, phase=SessionStatus.PHASE_TRAINING)
    for name, value in values.items():
        setattr(message, name, value)
    return message


def close_to(pixel, color, tolerance=12):
    return all(abs(int(a) - int(b)) <= tolerance for a, b in zip(pixel, color))


def test_headless_screenshot_shows_the_bodies_and_the_overlay(start_node, rclpy_context,
                                                              tmp_path):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    start_node('hrc_sim_node', 'sim_node', parameters={
        'pendulum_length': PENDULUM_LENGTH, 'marker_rate': 0.0})
    display = start_node('hrc_live', 'display_node', parameters={'port': 0, 'width': 800,
                                                                  'height': 480})
    # The test is the agent: the display reads these parameters through /agent.
    agent = rclpy.create_node('agent', context=rclpy_context)
    for name, value in (('max_training_episodes', 30), ('evaluation_episodes', 2),
                        ('episode_break', 4.0), ('mode', 'realtime')):
        agent.declare_parameter(name, value)
    executor = SingleThreadedExecutor(context=rclpy_context)
    executor.add_node(agent)

    def spin():
        executor.spin_once(timeout_sec=0.05)

    session_pub = agent.create_publisher(SessionStatus, topics.SESSION, qos.SESSION_QOS)
    state_pub = agent.create_publisher(TaskState, topics.STATE, qos.STATE_QOS)
    episode_pub = agent.create_publisher(EpisodeSummary, topics.EPISODE, qos.EPISODE_QOS)
    port = served_port(display)
    content_type, page = fetch(port, '/')
    assert content_type.startswith('text/html') and b'/frame.png' in page

    slider, angle, ball = 0.05, 0.2, 0.12
    session_pub.publish(session_status())

    def showing(step):
        spin()
        document = status(port)
        return (document['state'] is not None and document['state']['step'] == step
                and document['geometry_from_sim'] and document['plan'] is not None
                and document['session'] is not None)

    assert wait_for(lambda: (state_pub.publish(task_state(3, 7, slider, angle, ball)),
                             showing(7))[1], timeout=60, interval=0.2), display.output
    document = status(port)
    assert document['banner'] == ('Your turn: keep the slider in the middle of the rod and '
                                  'keep the ball in the middle of the pendulum')
    assert document['episode_label'] == 'Episode 4 of at most 30'
    assert 'You move the slider up and down (stick up = up).' in document['lines']

    content_type, png = fetch(port, '/frame.png')
    assert content_type == 'image/png'
    image = Image.open(io.BytesIO(png)).convert('RGB')
    assert image.size == (800, 480)
    image.save(tmp_path / 'display.png')  # the screenshot, kept with the test's files
    physics = PhysicsParams(pendulum_length=PENDULUM_LENGTH)
    frame = layout(physics, 800, 480)

    def at(y, z):
        column, row = frame.to_pixels(y, z)
        return image.getpixel((int(round(column)), int(round(row))))

    state = PhysicsState(7, 1.4, slider, 0.0, angle, 0.0, ball, 0.0, 0.0, 0.0, False, False)
    poses = body_poses(state, physics)
    assert close_to(at(poses['ball'][0][1], poses['ball'][0][2]), BALL_COLOR)
    along = 0.2 * PENDULUM_LENGTH
    assert close_to(at(along * math.cos(angle), slider + along * math.sin(angle)),
                    PENDULUM_COLOR)
    assert close_to(at(-0.018, slider), SLIDER_COLOR)
    assert close_to(at(0.0, -0.1), ROD_COLOR)
    # With the default 0.5 m beam the tip would be here; with the sim's 0.4 m it is background.
    assert close_to(at(0.47 * math.cos(angle), slider + 0.47 * math.sin(angle)),
                    BACKGROUND_COLOR)
    # The overlay: the banner and the panel carry text (many anti-aliased colours).
    banner = image.crop((0, 0, frame.scene_width, frame.banner_height))
    panel = image.crop((frame.scene_width, 0, 800, 240))
    assert len(banner.getcolors(100000)) > 20 and len(panel.getcolors(100000)) > 20

    # The episode ends: the result and the countdown to the next one.
    state_pub.publish(task_state(3, 200, slider, angle, ball, final=True))
    summary = EpisodeSummary(session_id='display-test', case_id=2, episode=3, steps=200,
                             human_involved=True, slider_error=0.012, pendulum_error=0.05,
                             ball_error=0.021, total_error=0.083, truncated=True)
    episode_pub.publish(summary)
    session_pub.publish(session_status(episode=4, total_episodes=4, human_involved_episodes=2))

    def result_shown():
        spin()
        document = status(port)
        return document['result'] and document['session']['total_episodes'] == 4

    assert wait_for(result_shown, timeout=30, interval=0.2), display.output
    document = status(port)
    assert document['result'][:2] == ['Episode 4 done', 'ball off centre: 2.1 cm on average']
    assert document['episode_label'] == 'Episode 5 of at most 30'
    if document['countdown']:  # a busy machine may have taken the whole 4 s break
        assert document['banner'] == f'Next episode in {document["countdown"]} s'
    else:
        assert document['banner'] == 'The next episode is starting'
    executor.shutdown()
    agent.destroy_node()
