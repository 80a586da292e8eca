"""The table of built-in controllers: each name's knowledge, law, settings and defaults on each arm.

:data:`CONTROLLERS` is the one table of built-in names
(:func:`~adaptive_dd.controllers.registry.make_controller` builds them, on any arm;
:func:`inventory` prints it for ``docs/controllers.md``).

Built-in settings:

``adaptive_ct``
    ``boost_bandwidth``, ``boost_duration``, ``observer``, ``observer_bandwidth``,
    ``estimator = {...}`` (fields of
    :class:`~adaptive_dd.identification.two_link_online_config.TwoLinkOnlineConfig`: ``tau_f``, ``split``,
    ``construction``, ``p0_payload``, ``p0_j2``, ``project``, ``align``), ``detector = {...}``
    (fields of :class:`~adaptive_dd.identification.two_link_online_config.ChangeDetector`; also
    accepted inside ``estimator``, as on an N-joint arm), or ``detector = false`` for none.
``slotine_li``
    ``gamma`` (seven adaptation gains).
``ct_nominal``, ``pd``
    ``sigma`` (the fixed model, seven base parameters).
``ct_oracle_late``
    ``delay`` [s]: how long after each swap its true model switches.
``sliding_mode`` (N-joint arms)
    ``uncertainty`` (the levels of ``[plant.uncertainty]``, by default the model's stated ones), ``max_mass``,
    ``com_radius`` (the payload's bound).
``composite``, ``icl``, ``craig_hsu_sastry`` (N-joint arms)
    ``slotine_li``'s ``gamma``, ``max_mass``, ``com_radius``.
``natural_adaptive`` (N-joint arms)
    ``gain`` (the natural law's one gain, derived by default), ``max_mass``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from adaptive_dd.controllers.adaptive import ADAPTIVE_ONLINE, BOOST_RULE, AdaptiveCT
from adaptive_dd.controllers.base import DEFAULT_MODEL_DELAY, Controller, Gains
from adaptive_dd.controllers.feedback import PD, ComputedTorque
from adaptive_dd.controllers.plugins import unknown_settings as _unknown
from adaptive_dd.controllers.slotine_li import COM_RADIUS, DEFAULT_GAMMA, MAX_MASS, SlotineLi, default_bounds
from adaptive_dd.errors import ParameterError
from adaptive_dd.identification.two_link_online import ChangeDetector, TwoLinkOnlineConfig

__all__ = ["ABSENT", "CONTROLLERS", "ONLINE_KEYS", "Builtin", "Setting", "inventory", "slotine_bounds"]

ONLINE_KEYS = {"tau_f", "split", "construction", "p0_payload", "p0_j2", "project", "align"}


def _sigma(spec: str, options: dict) -> np.ndarray:
    from adaptive_dd.plant.parameters import validate_sigma

    return validate_sigma(options["sigma"], f"controllers.{spec}.sigma")


def _online(spec: str, options: dict) -> TwoLinkOnlineConfig:
    est = dict(options.get("estimator", {}))
    det = options.get("detector", {})
    if "detector" in est:  # also accepted inside ``estimator``, as on an N-joint arm
        if "detector" in options:
            raise ParameterError(
                f"controllers.{spec}: 'detector' given twice (at the top and in 'estimator'); keep one"
            )
        det = est.pop("detector")
    _unknown(f"{spec}.estimator", est, ONLINE_KEYS)
    kw: dict[str, Any] = dict(est)
    if det is False:
        kw["detector"] = None
    elif isinstance(det, dict):
        fields = {f.name for f in dataclasses.fields(ChangeDetector)}
        _unknown(f"{spec}.detector", det, fields)
        kw["detector"] = ChangeDetector(**det)
    else:
        raise ParameterError(
            f"controllers.{spec}.detector: a table of detector settings or false, got {det!r}"
        )
    return dataclasses.replace(ADAPTIVE_ONLINE, **kw)


ABSENT = "-"
"""A setting's default on an arm where the controller does not take it (the table says why)."""


@dataclasses.dataclass(frozen=True)
class Setting:
    """One setting of a built-in controller: its default on each kind of arm and what it means.

    ``two_link`` / ``chain`` is the default on the two-link closed-form arm / on an N-joint
    :class:`~adaptive_dd.plant.arm.Arm`: a value (filled in when the table leaves the key out), None
    (the value is derived, as ``meaning`` says), or :data:`ABSENT` (not a setting on that arm:
    giving it is an error quoting ``rule``). ``rule`` says why the defaults differ, or why one
    arm lacks the setting. ``scenario_key`` False: derived from the scenario, set in code only
    (:data:`adaptive_dd.benchmark.scenario_settings.DERIVED` says from what)."""

    meaning: str
    two_link: Any = None
    chain: Any = None
    rule: str = ""
    unit: str = ""
    scenario_key: bool = True

    def default(self, kind: str) -> Any:
        return self.two_link if kind == "two_link" else self.chain


@dataclasses.dataclass(frozen=True)
class Builtin:
    """A built-in controller name: what it knows, its settings, and its form on each kind of arm.

    ``make(gains, settings, arm)`` builds the two-link form (None: N-joint only); ``chain`` names
    the N-joint class in :data:`~adaptive_dd.closed_loop.arena_laws.ARM_LAWS` (None:
    two-link only, ``only`` says why)."""

    knows: str
    law: str
    make: Callable[[Gains, dict, Any], Controller] | None
    chain: str | None
    settings: Mapping[str, Setting] = dataclasses.field(default_factory=dict)
    only: str = ""

    def applies_to(self, kind: str) -> bool:
        """Whether the controller runs on this kind of arm (``"two_link"`` or ``"chain"``)."""
        return (self.make if kind == "two_link" else self.chain) is not None

    def settings_on(self, kind: str) -> dict[str, Any]:
        """Settings the controller takes on this kind of arm, with their defaults there."""
        return {k: s.default(kind) for k, s in self.settings.items() if s.default(kind) is not ABSENT}


def _model(spec: str, o: dict, arm) -> np.ndarray:
    """The fixed model: the ``sigma`` setting, else the arm's base parameters."""
    return _sigma(spec, o) if o.get("sigma") is not None else arm.sigma


def _adaptive_ct_paper(g: Gains, o: dict, arm) -> Controller:
    from adaptive_dd.controllers.adaptive import adaptive_ct_paper

    ctrl = adaptive_ct_paper(g, arm.sigma)
    ctrl.online = dataclasses.replace(
        ctrl.online, payload_direction=tuple(float(x) for x in arm.payload_direction(0.0))
    )
    return ctrl


def _adaptive_ct(g: Gains, o: dict, arm) -> Controller:
    from adaptive_dd.closed_loop.controllers import _observer_settings  # the N-joint's checks and messages

    boost = {k: o[k] for k in ("boost_bandwidth", "boost_duration") if k in o}
    observer, bw = _observer_settings("adaptive_ct", o)
    online = dataclasses.replace(
        _online("adaptive_ct", o), payload_direction=tuple(float(x) for x in arm.payload_direction(0.0))
    )
    act = arm.actuator  # the boost keeps the command within the arm's torque limits
    lim = act.torque_limit if act.saturate else None
    return AdaptiveCT(
        online, g, arm.sigma, **boost, observer=observer, observer_bandwidth=bw, torque_limit=lim
    )


def _slotine_li(g: Gains, o: dict, arm) -> Controller:
    where = "controllers.slotine_li"
    for key in ("max_mass", "com_radius"):
        v = o[key]
        if isinstance(v, bool) or not isinstance(v, int | float) or not (np.isfinite(v) and v > 0):
            raise ParameterError(f"{where}.{key}: a number > 0, got {v!r}")
    bounds = slotine_bounds(arm, o["max_mass"], o["com_radius"])
    return SlotineLi(g, o["gamma"], arm.sigma, bounds=bounds)


_SIGMA = Setting(
    "the fixed model, seven base parameters (J1 J2 r b1 b2 d1 d2); default: the arm's",
    two_link=None,
    chain=ABSENT,
    rule="on an N-joint arm the controllers' model is the scenario's [model] table (docs/plant_and_model.md)",
)
_DELAY = Setting(
    "how long after each swap the true model switches [s], a whole number of samples (a law that "
    "learns each payload that late at best)",
    two_link=DEFAULT_MODEL_DELAY,
    chain=DEFAULT_MODEL_DELAY,
    unit="s",
)
_OBSERVER_RULE = (
    "one observer on every arm (the N-joint code, on the two-link arm with the paper's closed-form "
    "momentum: adaptive_dd.controllers.two_link_observer)"
)
_BOOST = {
    "boost_bandwidth": Setting(
        "bandwidth [rad/s] of the feedback for boost_duration after each alarm (through the nominal inertia)",
        300.0,
        300.0,
        unit="rad/s",
        rule="on an N-joint arm in a scenario the most per joint: each joint's is the largest whose sensor "
        "noise torque (3 std) stays inside its torque limit; at each sample it is scaled down as far as the "
        "command's limits need (adaptive_dd.closed_loop.boost)",
    ),
    "boost_duration": Setting(
        "how long the boost lasts after an alarm [s]",
        0.2,
        1.0,
        unit="s",
        rule=BOOST_RULE,
    ),
    "boost_ramp": Setting(
        "after boost_duration, the boost's added bandwidth falls linearly to none over this long [s] "
        "(0: it ends at once)",
        ABSENT,
        0.25,
        unit="s",
        rule="the ramped end is built for the N-joint adaptive_ct's law (docs/change_detection.md)",
    ),
    "observer": Setting(
        "feed forward the residual observer's torque (what the current model leaves unexplained, "
        "beyond 3 times its own noise level; docs/change_detection.md)",
        True,
        True,
        rule=_OBSERVER_RULE,
    ),
    "observer_bandwidth": Setting(
        "bandwidth of the residual observer's two stages [rad/s]; default 0.4 / T, T the sample period",
        None,
        None,
        rule=_OBSERVER_RULE,
        unit="rad/s",
    ),
    "estimator": Setting(
        "the estimator's settings: TwoLinkOnlineConfig's fields on the two-link arm (tau_f, split, "
        "construction, p0_payload, p0_j2, project, align), OnlineConfig's on an N-joint arm; "
        "not a scenario key (derived from the arm and the scenario: "
        "adaptive_dd.benchmark.scenario_settings), an option of make_controller",
        rule="two estimators: the paper's sigma with its splits; the payload's ten parameters",
        scenario_key=False,
    ),
    "detector": Setting(
        "the change detector's settings (ChangeDetector on the two-link arm, Detector on an N-joint "
        "arm), or false for none, at the top of the options (inside `estimator` with a FutureWarning); "
        "not a scenario key (derived from the arm and the scenario: "
        "adaptive_dd.benchmark.scenario_settings), an option of make_controller",
        rule="two detectors: GLR with persistence on sigma; a gate with a fast window on the payload",
        scenario_key=False,
    ),
}
_GAMMA_RULE = (
    "one gain per adapted parameter: sigma's seven on the two-link arm, the payload's ten on an N-joint arm"
)
_BOX_RULE = (
    "the box admits a payload up to max_mass, of size com_radius: on the two-link arm a disk of that "
    "radius at the tip (5 kg, 0.1 m: the paper's payloads), on an N-joint arm a centre of mass within "
    "com_radius of the payload frame (20 kg, 0.3 m: industrial arms' tools)"
)
_SLOTINE = {
    "gamma": Setting(
        "adaptation gains; default on an N-joint arm: derived from the arm and the reference, each "
        "parameter adapted at one rate, the fastest at half the feedback's lambda "
        "(adaptive_dd.closed_loop.adaptation_gain)",
        tuple(float(x) for x in DEFAULT_GAMMA),
        None,
        rule=_GAMMA_RULE,
    ),
    "max_mass": Setting("the heaviest payload the a-priori box admits [kg]", 5.0, 20.0, _BOX_RULE, "kg"),
    "com_radius": Setting("the payload's size in the a-priori box [m]", 0.1, 0.3, _BOX_RULE, "m"),
}
_N_JOINT_ONLY = (
    "built on the N-joint law kernel; the paper's two-link arm runs its own closed-form runtime: "
    "run the paper's arm from its URDF (benchmarks/scenarios/sice_drawn.toml)"
)
_NOT_TWO_LINK = "N-joint arms only: " + _N_JOINT_ONLY
_SLIDING = {
    "uncertainty": Setting(
        "the arm's parameter error levels bounding the model error (the keys of [plant.uncertainty]); "
        "default: the model's stated uncertainty ([model] uncertainty, else [plant.uncertainty]), "
        "none when it states none",
        ABSENT,
        None,
        rule=_NOT_TWO_LINK,
    ),
    "max_mass": Setting(
        "the heaviest payload the bound admits [kg]; default: [arm] payload_capacity, else 20",
        ABSENT,
        None,
        rule=_NOT_TWO_LINK,
        unit="kg",
    ),
    "com_radius": Setting(
        "the payload's centre of mass within this of the payload frame, per axis [m]",
        ABSENT,
        0.1,
        rule=_NOT_TWO_LINK,
        unit="m",
    ),
}
_TWO_LINK_ONLY = (
    "the paper's estimator (eq. 19, split 15) of the two-link arm's seven base parameters; "
    "on an N-joint arm use 'adaptive_ct'"
)


def _slotine_n_joint() -> dict:
    """slotine_li's settings for the payload-adaptive laws that run on N-joint arms only
    (composite, craig_hsu_sastry, icl): the same box, no two-link default."""
    return {k: dataclasses.replace(v, two_link=ABSENT, rule=_NOT_TWO_LINK) for k, v in _SLOTINE.items()}


CONTROLLERS: dict[str, Builtin] = {
    "pd": Builtin(
        "nominal model (inertia, to scale the gains)",
        "PD on the joint errors, gains scaled by the nominal inertia (q = 0 on the two-link arm, the "
        "middle of the joint ranges on an N-joint arm); no gravity compensation",
        lambda g, o, arm: PD(g, _model("pd", o, arm)),
        "pd",
        {"sigma": _SIGMA},
    ),
    "ct_nominal": Builtin(
        "nominal model",
        "computed torque (reference velocity) on the model without payload",
        lambda g, o, arm: ComputedTorque(g, _model("ct_nominal", o, arm)),
        "ct_nominal",
        {"sigma": _SIGMA},
    ),
    "ct_oracle": Builtin(
        "true model",
        "computed torque on the true model at every sample (the floor of adaptive_ct)",
        lambda g, o, arm: ComputedTorque(g, arm.sigma, oracle=True),
        "ct_oracle",
    ),
    "ct_oracle_textbook": Builtin(
        "true model",
        "the textbook computed torque: Coriolis and friction at the measured velocity",
        lambda g, o, arm: ComputedTorque(g, arm.sigma, oracle=True, reference_velocity=False),
        "ct_oracle_textbook",
    ),
    "ct_oracle_late": Builtin(
        "true model, told of each swap late",
        "ct_oracle whose true model switches delay after each swap: what knowing each payload that "
        "late costs the law (against ct_oracle)",
        lambda g, o, arm: ComputedTorque(g, arm.sigma, oracle=True, model_delay=o["delay"]),
        "ct_oracle_late",
        {"delay": _DELAY},
    ),
    "adaptive_ct_paper": Builtin(
        "estimator (the paper's)",
        "the paper's adaptive computed torque: eq. (19), split (15), eq. (14)",
        _adaptive_ct_paper,
        None,
        only=_TWO_LINK_ONLY,
    ),
    "adaptive_ct": Builtin(
        "estimator (payload swaps, with a change detector)",
        "computed torque on the online estimate, the feedback boosted after each alarm",
        _adaptive_ct,
        "adaptive_ct",
        _BOOST,
    ),
    "slotine_li": Builtin(
        "estimator (gradient adaptation)",
        "Slotine-Li adaptive control, estimates projected on an a-priori box",
        _slotine_li,
        "slotine_li",
        _SLOTINE,
    ),
    "slotine_li_oracle": Builtin(
        "true model",
        "Slotine-Li with the true model and no adaptation (the floor of slotine_li)",
        lambda g, o, arm: SlotineLi(g, theta0=arm.sigma, bounds=slotine_bounds(arm), oracle=True),
        "slotine_li_oracle",
    ),
    "pd_gravity": Builtin(
        "nominal model (gravity, and the inertia to scale the gains)",
        "PD plus the nominal model's gravity torque (Takegaki and Arimoto 1981)",
        None,
        "pd_gravity",
        only=_N_JOINT_ONLY,
    ),
    "pd_gravity_oracle": Builtin(
        "true model (gravity)",
        "PD plus the true gravity torque (the floor of pd_gravity)",
        None,
        "pd_gravity_oracle",
        only=_N_JOINT_ONLY,
    ),
    "sliding_mode": Builtin(
        "nominal model and a bound of its error",
        "robust computed torque with a boundary layer, the bound from the stated uncertainty "
        "(Slotine 1985; Spong 1992)",
        None,
        "sliding_mode",
        _SLIDING,
        only=_N_JOINT_ONLY,
    ),
    "composite": Builtin(
        "estimator (gradient adaptation and the filtered torque's prediction error)",
        "Slotine and Li's composite adaptive control on the payload (Automatica 1989), slotine_li's box",
        None,
        "composite",
        _slotine_n_joint(),
        only=_N_JOINT_ONLY,
    ),
    "craig_hsu_sastry": Builtin(
        "estimator (adaptation through the inverse of the estimated inertia; measured acceleration)",
        "Craig, Hsu and Sastry's adaptive computed torque on the payload (IJRR 1987), slotine_li's box "
        "and a physically consistent payload",
        None,
        "craig_hsu_sastry",
        _slotine_n_joint(),
        only=_N_JOINT_ONLY,
    ),
    "icl": Builtin(
        "estimator (gradient adaptation and a history stack of integrated torque and regressor)",
        "integral concurrent learning on the payload (Parikh, Kamalapurkar and Dixon 2019), slotine_li's box",
        None,
        "icl",
        _slotine_n_joint(),
        only=_N_JOINT_ONLY,
    ),
    "natural_adaptive": Builtin(
        "estimator (natural gradient on the payload link's pseudo-inertia)",
        "the natural adaptive law on the payload's link (Lee, Kwon and Park 2018), physically "
        "consistent at every sample",
        None,
        "natural_adaptive",
        {
            "gain": Setting(
                "the natural law's one gain gamma; default slotine_li's mass gain / "
                "(link mass + max_mass / 2)^2",
                ABSENT,
                None,
                rule=_NOT_TWO_LINK,
            ),
            "max_mass": Setting(
                "the heaviest payload the law adapts to [kg]; default: [arm] payload_capacity, else 20",
                ABSENT,
                None,
                rule=_NOT_TWO_LINK,
                unit="kg",
            ),
        },
        only=_N_JOINT_ONLY,
    ),
    "momentum_observer_ct": Builtin(
        "nominal model and the applied torque",
        "computed torque on the nominal model plus the generalized-momentum observer's residual "
        "(De Luca et al. 2005)",
        None,
        "momentum_observer_ct",
        only=_N_JOINT_ONLY,
    ),
}
"""Every built-in controller name, on every arm: what it knows, its law, its settings with their
default on each arm (and the rule where they differ), and its two forms. A new built-in: one
entry here (and its N-joint class in :mod:`adaptive_dd.closed_loop.controllers`)."""


def slotine_bounds(arm, max_mass: float = MAX_MASS, com_radius: float = COM_RADIUS) -> tuple:
    """Slotine-Li's a-priori box on a two-link arm (:func:`.slotine_li.default_bounds`)."""
    return default_bounds(arm.sigma, arm, max_mass, com_radius)


def _show(v: Any) -> str:
    if v is ABSENT:
        return "not a setting"
    if v is None:
        return "see the meaning"
    if isinstance(v, tuple):
        return "(" + ", ".join(f"{x:g}" for x in v) + ")"
    return f"{v:g}" if isinstance(v, float) else str(v)


def inventory() -> str:
    """The table of every built-in name and setting on both arms, as Markdown.

    ``docs/controllers.md`` holds it; ``tests/test_controller_registry.py`` checks the page
    against this.

    Returns
    -------
    str
        A Markdown table: controller, what it knows, arms, setting, defaults on each arm, rule.

    Examples
    --------
    >>> from adaptive_dd.controllers.registry import inventory
    >>> print(inventory().splitlines()[0])
    | controller | knows | arms | setting | two-link default | N-joint default | rule where they differ |
    """
    rows = [
        "| controller | knows | arms | setting | two-link default | N-joint default | rule where they differ"
        " |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, e in CONTROLLERS.items():
        if e.applies_to("chain") and e.applies_to("two_link"):
            arms = "both"
        elif e.applies_to("chain"):
            arms = "N-joint only (the paper's arm: from its URDF, benchmarks/scenarios/sice_drawn.toml)"
        else:
            arms = f"two-link only ({e.only})"
        first = f"| `{name}` | {e.knows} | {arms} |"
        if not e.settings:
            rows.append(f"{first} none | | | |")
        for i, (k, st) in enumerate(e.settings.items()):
            lead = first if i == 0 else "| | | |"
            defaults = f"{_show(st.two_link)} | {_show(st.chain)}"
            rows.append(f"{lead} `{k}`: {st.meaning} | {defaults} | {st.rule or 'same'} |")
    return "\n".join(rows)
