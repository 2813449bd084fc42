"""Parameters of the display node (pure: no rclpy, so tools and tests import them alone)."""

from dataclasses import dataclass

from hrc_common.params import param


@dataclass
class DisplayParams:
    """Parameters of the display node (node ``display``, params/display.yaml)."""

    port: int = param(8765, 'TCP port of the pages on 127.0.0.1 (localhost only); 0 = any free '
                      'port (logged)', low=0, high=65535)
    words_rate: float = param(5.0, 'how often the words and the console are recomputed and '
                              'pushed when changed (Hz); states are pushed as they come',
                              low=0.5, high=30.0)
    result_seconds: float = param(5.0, 'the result of an episode stays up during the break '
                                  'and this long into the next episode (s)', low=0.0,
                                  high=600.0)
    tlx_file: str = param('', 'file the raw NASA-TLX answers are appended to (YAML, mode '
                          '0600); empty = no questionnaire on the page')
    tlx_title: str = param('', 'what the questionnaire asks about, shown above it (e.g. the '
                           'condition without naming the case)')
    subject_id: str = param('', 'pseudonymous subject id shown on the console (never on the '
                            "person's page); empty = no subject")
    condition: str = param('', "the condition and its place in the subject's order, shown on "
                           'the console (e.g. "condition 2 of 6 in the order (case 3)")')
    gamepad: bool = param(
        False, "take the person's gamepad from their page (the browser's Gamepad API, POST "
        '/gamepad) and publish it on /joy for the human node (input: joy); the publisher '
        'exists only while a gamepad sends, so a runner sees no input without one')
    sim_node: str = param('sim', 'node whose parameters give the geometry and timing')
    agent_node: str = param('agent', 'node whose parameters give the episode counts and the '
                            'break between episodes')
    query_period: float = param(1.0, 'interval between attempts to read the sim and agent '
                                'parameters until they answer (s)', low=0.05, high=60.0)
