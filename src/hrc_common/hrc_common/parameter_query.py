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
    """Read some parameters of another node once, through its get_parameters service."""

    def __init__(self, node: Node, target: str, names, on_values,
                 answer_timeout: float = ANSWER_TIMEOUT_S, clock=time.monotonic):
        self.node = node
        self.answer_timeout = answer_timeout
        self._clock = clock
        self._asked_at = 0.0
        self.target = target.lstrip('/')
        self.names = list(names)
        self.on_values = on_values
        self.client = node.create_client(GetParameters, f'/{self.target}/get_parameters')
        self.future = None
        self.done = False

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
        if not self.client.service_is_ready():
            return
        self._asked_at = now
        future = self.future = self.client.call_async(GetParameters.Request(names=self.names))
        future.add_done_callback(self._on_answer)

    def restart(self) -> None:
        """Ask again (the node was restarted, e.g. a new session)."""
        self.done = False

    def _on_answer(self, future) -> None:
        if future is not self.future:
            return   # a request given up on (asked again since)
        self.future = None
        try:
            values = [parameter_value_to_python(value) for value in future.result().values]
        except Exception as error:  # the service call failed: try again later
            self.node.get_logger().warning(f'reading parameters of /{self.target} failed: '
                                           f'{error}', throttle_duration_sec=10.0)
            return
        if len(values) != len(self.names) or any(value is None for value in values):
            self.node.get_logger().warning(
                f'/{self.target} lacks some of the parameters {self.names}: got {values}',
                throttle_duration_sec=10.0)
            return
        self.done = True
        self.on_values(dict(zip(self.names, values)))
