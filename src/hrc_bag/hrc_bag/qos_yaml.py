"""QoS profiles in the YAML form of rosbag2 (metadata version 9), pure (no rclpy import).

rosbag2 stores the QoS profiles the publishers of a topic offered (``offered_qos_profiles``):
in the MCAP channel metadata as a YAML string, in ``metadata.yaml`` (version 9) as a list. Each
profile is a mapping::

    history: keep_last          # keep_last | keep_all | system_default | unknown
    depth: 10
    reliability: reliable       # reliable | best_effort | system_default | best_available | ...
    durability: volatile        # volatile | transient_local | ...
    deadline: {sec: 9223372036, nsec: 854775807}   # RMW_DURATION_INFINITE
    lifespan: {sec: ..., nsec: ...}
    liveliness: automatic       # automatic | manual_by_topic | ...
    liveliness_lease_duration: {sec: ..., nsec: ...}
    avoid_ros_namespace_conventions: false

Policies are written as the lower-case names rmw uses (rmw_qos_*_policy_to_str); durations as
seconds and nanoseconds.
"""

from hrc_common import bounded_yaml
from hrc_common.contract import NS_PER_S as NANOSECONDS
import yaml

_DUMPER = getattr(yaml, 'CSafeDumper', yaml.SafeDumper)

# Durations this long or longer mean "infinite" (older rmw wrote other sentinel values).
INFINITE_THRESHOLD_NS = 0x7FFFFFFF * NANOSECONDS


def load_yaml(text: str, source: str = 'YAML'):
    """Parse YAML (safe types only) within the bounds of hrc_common.bounded_yaml."""
    return bounded_yaml.load(text, source)


def dump_yaml(document) -> str:
    """Return block-style YAML (safe types only) in the key order given."""
    return yaml.dump(document, Dumper=_DUMPER, default_flow_style=False, sort_keys=False,
                     allow_unicode=True)


def _policy_name(value) -> str:
    """Return the rmw string of a QoS policy enum (rclpy enums have ``name``)."""
    name = getattr(value, 'name', None)
    if name is None:
        return str(value).lower()
    return name.lower()


def _duration_dict(duration) -> dict:
    nanoseconds = int(getattr(duration, 'nanoseconds', duration))
    return {'sec': nanoseconds // NANOSECONDS, 'nsec': nanoseconds % NANOSECONDS}


def profile_to_dict(profile) -> dict:
    """Return the rosbag2 (v9) mapping of a QoS profile (an rclpy QoSProfile or alike)."""
    return {
        'history': _policy_name(profile.history),
        'depth': int(profile.depth),
        'reliability': _policy_name(profile.reliability),
        'durability': _policy_name(profile.durability),
        'deadline': _duration_dict(profile.deadline),
        'lifespan': _duration_dict(profile.lifespan),
        'liveliness': _policy_name(profile.liveliness),
        'liveliness_lease_duration': _duration_dict(profile.liveliness_lease_duration),
        'avoid_ros_namespace_conventions': bool(profile.avoid_ros_namespace_conventions),
    }


def dump_profiles(profiles: list) -> str:
    """Return the YAML string of a list of profile mappings (MCAP channel metadata form)."""
    if not profiles:
        return ''
    return dump_yaml(list(profiles))


def load_profiles(text) -> list:
    """Return the list of profile mappings from a YAML string (or an already parsed list)."""
    if not text:
        return []
    profiles = load_yaml(text) if isinstance(text, str) else text
    if not isinstance(profiles, list):
        raise ValueError(f'offered_qos_profiles is not a list: {profiles!r}')
    return profiles


def duration_ns(value: dict) -> int:
    """Return nanoseconds of a ``{sec, nsec}`` mapping; 0 (= rmw default) for infinite."""
    nanoseconds = int(value.get('sec', 0)) * NANOSECONDS + int(value.get('nsec', 0))
    return 0 if nanoseconds >= INFINITE_THRESHOLD_NS else nanoseconds
