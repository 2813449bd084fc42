"""Fixtures shared by every test: a private ROS domain per test and node processes."""

import pathlib
import sys

import pytest

from hrc_common.domains import DomainReservation

# The test support (test/support/hrc_testing) lives with the tests, not in an installed package.
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent / 'test' / 'support'))
from hrc_testing.nodes import NodeProcess, read_bag_with_rosbags, ros_environment  # noqa: E402


@pytest.fixture
def ros_domain_id(monkeypatch):
    """Give the test a ROS_DOMAIN_ID of its own, also set for the test process itself.

    The id is reserved with a lock file for the test's duration, so that concurrent test runs
    on the same machine never share a domain.
    """
    reservation = DomainReservation()
    for name, value in ros_environment(reservation.domain_id).items():
        if name.startswith(('ROS_', 'FASTDDS_')):
            monkeypatch.setenv(name, value)
    monkeypatch.delenv('ROS_LOCALHOST_ONLY', raising=False)
    yield reservation.domain_id
    reservation.release()


@pytest.fixture
def ros_env(ros_domain_id):
    """Return the environment for node subprocesses on the test's domain."""
    return ros_environment(ros_domain_id)


@pytest.fixture
def rclpy_context(ros_domain_id):
    """Give an rclpy context on the test's domain, shut down after the test."""
    import rclpy
    from rclpy.context import Context

    context = Context()
    rclpy.init(context=context, domain_id=ros_domain_id)
    yield context
    if context.ok():
        rclpy.shutdown(context=context)


@pytest.fixture
def start_node(ros_env, request):
    """Start node executables in separate processes; they are stopped after the test.

    Usage: ``start_node('hrc_sim_node', 'sim_node', parameters={'mode': 'lockstep'})``. When the
    test fails, each node's output is printed to help the diagnosis.
    """
    processes = []

    def start(package, executable, **kwargs):
        kwargs.setdefault('env', ros_env)
        process = NodeProcess(package, executable, **kwargs)
        processes.append(process)
        return process

    yield start
    for process in processes:
        process.stop()
    failed = getattr(request.node, 'rep_call', None)
    if failed is not None and failed.failed:
        for process in processes:
            print(f'----- output of {process.name} -----\n{process.output}')
    for process in processes:
        process.remove_log()


# The quick tier (``make test-quick``, ``pytest -m quick``): pure cores and unit tests, for the
# inner loop of development. A test is left out of it when it talks DDS (one of these fixtures),
# drives a browser, or is marked slow (whole sessions, training, Ray, a graph of nodes).
DDS_FIXTURES = {'ros_domain_id', 'ros_env', 'rclpy_context', 'start_node'}


def pytest_collection_modifyitems(config, items):
    """Mark each test ``dds``/``browser`` by what it uses, and ``quick`` if it is neither/slow."""
    for item in items:
        if DDS_FIXTURES & set(getattr(item, 'fixturenames', ())):
            item.add_marker(pytest.mark.dds)
        module = getattr(item, 'module', None)
        if module is not None and hasattr(module, 'open_browser'):
            item.add_marker(pytest.mark.browser)
        if not any(item.get_closest_marker(name) for name in ('dds', 'browser', 'slow')):
            item.add_marker(pytest.mark.quick)


@pytest.hookimpl(wrapper=True, tryfirst=True)
def pytest_runtest_makereport(item, call):
    """Keep each phase's report on the item so fixtures can see whether the test failed."""
    report = yield
    setattr(item, 'rep_' + report.when, report)
    return report


@pytest.fixture(scope='session')
def rosbags_typestore():
    """Return the serializer's rosbags typestore: ROS 2 Jazzy plus the installed hrc_msgs."""
    from hrc_bag import serializer

    return serializer.typestore()


@pytest.fixture
def read_rosbag(rosbags_typestore):
    """Return a function reading a rosbag2 folder with rosbags: {topic: [decoded messages]}."""
    return lambda folder: read_bag_with_rosbags(rosbags_typestore, folder)
