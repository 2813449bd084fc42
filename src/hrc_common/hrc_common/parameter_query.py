"""Read parameters of another node at run time, through its ``get_parameters`` service.

How a node learns what another node owns instead of repeating it in its own YAML: the human
node and the display read the sim's control period and limits (and the display its geometry)
from the running sim. rclpy; no spinning of its own: the owner node's timer calls
:meth:`ParameterQuery.poll` until the answer came.
"""

import time

from rcl_interfaces.srv import GetParameters
from rclpy.node import Node
from rclpy.parameter import parameter_value_to_python


# s: a request without an answer this long is asked again. A service's answer can be lost: the
# client sees the service as ready once its request reaches it, but the service may not have
# matched the client's response reader yet (its response is then dropped), and a service
# restarted in between never answers the old request. Seen once in ~20 graph starts under load:
# the human node then waited for the sim's limits forever.
ANSWER_TIMEOUT_S = 2.0


class ParameterQuery:
    """Read some parameters of another node once, through its get_parameters service.

    ``names`` are needed, ``optional`` ones taken when the node has them (an older or another
    sim may not). rclpy answers a request that names one parameter the node lacks with no
    value at all, so an incomplete answer is followed by one request per name: the values the
    node has are taken, and the warning names the needed parameters it lacks.
    """

    def __init__(self, node: Node, target: str, names, on_values,
                 answer_timeout: float = ANSWER_TIMEOUT_S, clock=time.monotonic, optional=()):
        self.node = node
        self.answer_timeout = answer_timeout
        self._clock = clock
        self._asked_at = 0.0
        self.target = target.lstrip('/')
        self.names = list(names)
        self.optional = [name for name in optional if name not in self.names]
        self.on_values = on_values
        self.client = node.create_client(GetParameters, f'/{self.target}/get_parameters')
        self.future = None
        self.done = False
        self._one_by_one = None     # {name: value or None} once asked a name at a time
        self._retry_at = 0.0        # clock s: the next round after needed ones were missing
        self.lacking = []           # the needed parameters the node lacked when last asked

    @property
    def service(self) -> str:
        """The name of the service asked."""
        return self.client.srv_name

    def poll(self) -> None:
        """Ask (again) if not answered yet and the service is there.

        A request unanswered for ``answer_timeout`` s is dropped and asked again.
        """
        if self.done:
            return
        now = self._clock()
        if self.future is not None:
            if now - self._asked_at < self.answer_timeout:
                return
            self.client.remove_pending_request(self.future)
            self.future = None
            self.node.get_logger().info(f'no answer from {self.service} within '
                                        f'{self.answer_timeout:g} s: asking again')
        if now < self._retry_at or not self.client.service_is_ready():
            return
        self._asked_at = now
        asked = self._next_names()
        future = self.future = self.client.call_async(GetParameters.Request(names=asked))
        future.add_done_callback(lambda done: self._on_answer(done, asked))

    def restart(self) -> None:
        """Ask again (the node was restarted, e.g. a new session)."""
        self.done = False
        self._one_by_one = None

    def _next_names(self) -> list:
        if self._one_by_one is None:
            return self.names + self.optional
        return [next(name for name in self.names + self.optional
                     if name not in self._one_by_one)]

    def _on_answer(self, future, asked: list) -> None:
        if future is not self.future:
            return   # a request given up on (asked again since)
        self.future = None
        try:
            values = [parameter_value_to_python(value) for value in future.result().values]
        except Exception as error:  # the service call failed: try again later
            self.node.get_logger().warning(f'reading parameters of /{self.target} failed: '
                                           f'{error}', throttle_duration_sec=10.0)
            return
        if self._one_by_one is None:
            if len(values) == len(asked) and all(value is not None for value in values):
                self._finish(dict(zip(asked, values)))
                return
            self._one_by_one = {}      # incomplete: find out which, a name at a time
            return
        self._one_by_one[asked[0]] = values[0] if len(values) == 1 else None
        if len(self._one_by_one) == len(self.names) + len(self.optional):
            self._judge(self._one_by_one)

    def _judge(self, found: dict) -> None:
        """Take the values asked one by one, or say which needed ones the node lacks."""
        lacking = self.lacking = [name for name in self.names if found[name] is None]
        if lacking:
            has = [name for name, value in found.items() if value is not None]
            self.node.get_logger().warning(
                f'/{self.target} lacks the parameters {lacking} (it has {has}): waiting for '
                f'a /{self.target} that has them', throttle_duration_sec=10.0)
            self._one_by_one = None
            self._retry_at = self._clock() + self.answer_timeout
            return
        absent = [name for name in self.optional if found[name] is None]
        if absent:
            self.node.get_logger().info(f'/{self.target} has not the optional parameters '
                                        f'{absent}: their defaults are used')
        self._finish({name: value for name, value in found.items() if value is not None})

    def _finish(self, values: dict) -> None:
        self.done = True
        self._one_by_one = None
        self.on_values(values)
