"""The environments' session-level settings from the one session configuration. Pure.

``SliderPendulumBallEnv(session=SessionSettings(...))`` runs the session's case, seed, profile
and ``sim.*`` overrides (:class:`hrc_common.session_plan.SessionSettings`, the configuration
``hrc session``, the in-process engine and the experiment take): the physics is the session's
sim (``params/sim.yaml`` with the overrides, composed by ``session_plan.compose``), the human
the session's profile (``--profile`` or ``--set human.profile``), the reward the preset of the
session's learning configuration (``session.learning``: ``params/learning/<name>.yaml``), and
the first ``reset()`` without a seed is seeded with the session's seed. The environment's own
keywords (``training_step``, ``observe_rates``) stay keywords; ``case``, ``human`` and
``preset`` come from one place only: given both ways they are refused.
"""

from dataclasses import replace

from hrc_common.params import from_dict, ParameterError
from hrc_common.paths import params_dir
from hrc_common.session_plan import compose, SessionSettings
from hrc_sim_node.physics import physics_params_of
from hrc_sim_node.sim_params import SimParams

# The overrides an environment can apply: the sim's parameters make the physics; the human's
# profile picks the simulated human. The agent is the learner's own, the recorder is absent.
APPLICABLE_OVERRIDES = ('sim.*', 'human.profile')


def session_keywords(session: SessionSettings, keywords: dict, physics_params) -> tuple:
    """Return (keywords, physics parameters) of an environment running ``session``.

    ``keywords``: the environment's other keywords (``case`` and ``human`` must not be among
    them). Raises ParameterError with every reason at once.
    """
    reasons = list(session.check()) if isinstance(session, SessionSettings) else [
        f'session: expected a SessionSettings, got {type(session).__name__}']
    if reasons:
        raise ParameterError('session rejected: ' + '; '.join(reasons), reasons)
    for name, source in (('case', 'session.case'),
                         ('human', "session.human_profile or overrides['human.profile']"),
                         ('preset', "session.learning's reward preset")):
        if name in keywords:
            reasons.append(f'{name}: given by the session ({source}); pass it once')
    if physics_params is not None:
        reasons.append("physics_params: given by the session (params/sim.yaml and its 'sim.*' "
                       'overrides); pass it once')
    for key in session.overrides:
        if not (key.startswith('sim.') or key == 'human.profile'):
            reasons.append(f'overrides {key!r}: an environment applies '
                           f'{" and ".join(APPLICABLE_OVERRIDES)} only')
    if reasons:
        raise ParameterError('session rejected: ' + '; '.join(reasons), reasons)
    # record False: no recorder section to compose (an environment records nothing)
    parameters = compose(replace(session, record=False), params_dir())
    sim = from_dict(SimParams, parameters['sim'])
    return (dict(keywords, case=session.case, human=parameters['human']['profile'],
                 preset=parameters['agent']['preset']), physics_params_of(sim))
