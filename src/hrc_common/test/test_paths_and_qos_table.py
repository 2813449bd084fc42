"""The one params-directory lookup (hrc_common.paths) and the one QoS table (qos_table)."""

import pathlib
import re

from hrc_common import paths, qos, qos_table, topics
from rclpy.qos import DurabilityPolicy, HistoryPolicy, ReliabilityPolicy

REPOSITORY = pathlib.Path(__file__).resolve().parents[3]


def test_a_checkout_uses_its_own_params():
    assert paths.params_dir() == REPOSITORY / 'params'
    assert paths.params_file('cases.yaml') == REPOSITORY / 'params' / 'cases.yaml'


def test_outside_a_checkout_the_installed_share_is_used(monkeypatch, tmp_path):
    monkeypatch.setattr(paths, '_CHECKOUT', tmp_path)     # no src/, no params/ there
    installed = paths.params_dir()
    assert installed.parts[-3:] == ('share', 'hrc_common', 'params')
    # every parameter and data file is installed there (hrc_common/setup.py)
    assert {path.name for path in (REPOSITORY / 'params').glob('*.yaml')} <= \
        {path.name for path in installed.glob('*.yaml')}


def test_the_rclpy_profiles_are_the_table():
    assert set(qos_table.OF_TOPIC) == set(topics.TYPES) == set(qos.OF_TOPIC)
    for topic, spec in qos_table.OF_TOPIC.items():
        profile = qos.OF_TOPIC[topic]
        assert profile.history == HistoryPolicy.KEEP_LAST
        assert profile.depth == spec.depth
        assert (profile.reliability == ReliabilityPolicy.RELIABLE) == spec.reliable
        assert profile.durability == (DurabilityPolicy.TRANSIENT_LOCAL if spec.transient_local
                                      else DurabilityPolicy.VOLATILE)
        assert profile.deadline.nanoseconds == spec.deadline_ns


def test_the_table_is_the_documented_one():
    # docs/architecture.md, "Topics": | `/hrc/state` | ... | reliable, keep_last 10 |
    documented = {}
    for line in (REPOSITORY / 'docs' / 'architecture.md').read_text().splitlines():
        match = re.match(r'\| `(/[\w/]+)` \|.*\| ([^|]+) \|$', line)
        if match:
            documented[match.group(1)] = match.group(2).strip()
    for topic, spec in qos_table.OF_TOPIC.items():
        words = ['reliable' if spec.reliable else 'best effort']
        if spec.transient_local:
            words.append('transient_local')
        words.append(f'keep_last {spec.depth}')
        if spec.deadline_ns:
            words.append(f'deadline {spec.deadline_ns / 1e9:g} s')
        assert documented[topic] == ', '.join(words), topic
