"""Test support of hrc: helpers shared by the tests (and some benchmarks), not installed.

``conftest.py`` at the repository's root puts ``test/support/`` on ``sys.path`` for every test;
a benchmark under ``bench/`` that uses a helper does the same. Modules:

* :mod:`hrc_testing.nodes`: node processes over DDS, a test's ROS environment, waiting;
* :mod:`hrc_testing.sessions`: an easy task tree, exact digests of sessions;
* :mod:`hrc_testing.bag_traffic`: synthetic session traffic for the recorder, replay and report;
* :mod:`hrc_testing.recorder_kill`: SIGKILL a recorder mid-session and compare its bags;
* :mod:`hrc_testing.study_records`: seeded synthetic SessionRecords for the study's findings.
"""
