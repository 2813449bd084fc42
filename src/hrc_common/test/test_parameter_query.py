"""ParameterQuery asks again when its request is never answered.

In one graph start of about twenty the human node sent its request for the sim's limits and
never got an answer: it waited forever and the sim counted every human command missing. Here
the answer is lost for sure: the service that received the request is destroyed unanswered
and a new one takes its place; the query must ask again and get the values.
"""

import time

from rcl_interfaces.msg import ParameterType, ParameterValue
from rcl_interfaces.srv import GetParameters

from hrc_common.executors import LeanExecutor
from hrc_common.parameter_query import ParameterQuery


def test_a_request_never_answered_is_asked_again(rclpy_context):
    import rclpy
    asker = rclpy.create_node('asker', context=rclpy_context)
    owner = rclpy.create_node('owner', context=rclpy_context)
    requests = []

    def answer(request, response):
        requests.append(list(request.names))
        response.values = [ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=0.2)]
        return response

    service = owner.create_service(GetParameters, '/fake_sim/get_parameters', answer)
    values = []
    # The query's clock is the test's (s): "within the timeout" holds however slow the machine.
    now = [0.0]
    query = ParameterQuery(asker, 'fake_sim', ['control_period'], values.append,
                           answer_timeout=1.0, clock=lambda: now[0])
    asking = LeanExecutor(context=rclpy_context)
    asking.add_node(asker)
    deadline = time.monotonic() + 30
    while query.future is None:          # the service is seen: the request goes out
        assert time.monotonic() < deadline
        query.poll()
        asking.spin_once(timeout_sec=0.05)
    lost = query.future
    # The owner never serves that request: its service goes away with it, a new one comes.
    # (The pause lets the request reach the old service; were it shorter, the new one could get
    # the request and the test would prove less, but it would not fail.)
    time.sleep(0.3)
    owner.destroy_service(service)
    owner.create_service(GetParameters, '/fake_sim/get_parameters', answer)
    answering = LeanExecutor(context=rclpy_context)
    answering.add_node(owner)
    query.poll()
    assert query.future is lost           # within the timeout: still waiting
    now[0] += 1.5                         # past the timeout
    deadline = time.monotonic() + 30
    while not values:
        assert time.monotonic() < deadline, 'the query never asked again'
        query.poll()
        asking.spin_once(timeout_sec=0.02)
        answering.spin_once(timeout_sec=0.02)
    assert values == [{'control_period': 0.2}] and query.done
    assert requests == [['control_period']]    # the lost request was never served
    asking.shutdown()
    answering.shutdown()
    asker.destroy_node()
    owner.destroy_node()


def _ask_until(query, executor, condition, timeout=120.0):
    deadline = time.monotonic() + timeout       # generous: discovery on a busy machine
    while not condition() and time.monotonic() < deadline:
        query.poll()
        executor.spin_once(timeout_sec=0.05)
    return condition()


def test_a_node_without_some_parameters_is_named_and_optional_ones_are_skipped(rclpy_context):
    """A sim without an optional parameter was answered with nothing: the node waited forever.

    rclpy answers a request naming a parameter the node lacks with no value at all; the query
    then asks name by name, takes what the node has and names the needed ones it lacks.
    """
    import rclpy
    from rclpy.parameter import Parameter
    asker = rclpy.create_node('asker', context=rclpy_context)
    older_sim = rclpy.create_node('older_sim', context=rclpy_context, parameter_overrides=[
        Parameter('control_period', value=0.2), Parameter('max_force', value=10.0)],
        automatically_declare_parameters_from_overrides=True)
    executor = LeanExecutor(context=rclpy_context)
    executor.add_node(asker)
    executor.add_node(older_sim)
    values = []
    now = [0.0]
    needs_torque = ParameterQuery(asker, 'older_sim', ['control_period', 'max_force',
                                                       'max_torque'], values.append,
                                  clock=lambda: now[0], optional=['human_period'])
    assert _ask_until(needs_torque, executor, lambda: needs_torque.lacking)
    assert needs_torque.lacking == ['max_torque'] and not needs_torque.done and values == []
    takes_what_is_there = ParameterQuery(asker, 'older_sim', ['control_period', 'max_force'],
                                         values.append, clock=lambda: now[0],
                                         optional=['human_period'])
    assert _ask_until(takes_what_is_there, executor, lambda: takes_what_is_there.done)
    assert values == [{'control_period': 0.2, 'max_force': 10.0}]
    executor.shutdown()
    asker.destroy_node()
    older_sim.destroy_node()
