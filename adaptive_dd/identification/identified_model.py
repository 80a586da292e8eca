"""An identified arm model on disk: ``model.json`` (and ``model.urdf``), written by ``identify --out``.

``model.json`` holds what another part of the project needs to start from an identified
arm rather than from its URDF: the URDF it was identified on (and how it was read), the
base parameters with their names, values, covariance and whether each was identified (or
held at the URDF's value), the noise levels, friction and armature, and where it came from
(record, window, filter). When a physically consistent set of standard parameters fits the
estimate, ``model.urdf`` is the URDF with those inertias, friction and damping written in
(the armature, which URDF cannot hold, stays in ``model.json``).

The model names the arm it belongs to by content, not by path (:func:`arm_identity`): a hash of
the chain's kinematics (joint names, types, axes, placements, gravity, payload frame) and of the
parameters the identification fixed (the URDF's values of the base parameters it held), with
those values beside it, so that a byte-identical copy of the URDF is the same arm and another
arm is told apart with what differs (:func:`identity_differences`).

Load it with :func:`load_identified_model`::

    from adaptive_dd.identification.identified_model import load_identified_model
    m = load_identified_model("results/tiago/model.json")
    arm = m.arm()                      # the Arm (URDF, friction and armature identified)
    tau = m.predict(q, qd, qdd)        # joint torques of the identified base parameters
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.errors import DataError, is_finite_number

__all__ = [
    "FORMAT",
    "IdentifiedModel",
    "arm_identity",
    "identity_differences",
    "load_identified_model",
    "save_identified_model",
]

Array = NDArray[np.float64]
FORMAT = "adaptive_dd identified model 1"


@dataclass(frozen=True)
class IdentifiedModel:
    """What ``model.json`` holds (module docstring); per-joint lists have n entries, others p.

    Attributes
    ----------
    urdf : str
        The URDF identified on (absolute path).
    payload_frame : str
    gravity : list of float
    repair_inertia : bool
    joint_names : list of str
    friction_velocity : float
        ``v_f`` of the Coulomb law ``fc tanh(qd / v_f)`` [rad/s] the arm is handed (:meth:`arm`).
    names : list of str
        Base parameter names.
    sigma, sigma_urdf, std : list of float
    identified : list of bool
    covariance : list of list of float
    used : list of bool
        Torque channels fitted.
    residual_rms, noise_rms : list of float
        Filtered residual and sensor noise per channel [N m] (nan: excluded).
    viscous, coulomb, armature : list of float
        Per joint [N m s, N m, kg m^2] (the consistent fit's, else the URDF's or identified ones).
    consistent_sigma : list of float or None
        Base parameters of the nearest physically consistent arm.
    consistent_distance : float or None
        Its distance from the estimate [std].
    fitted_urdf : str or None
        ``model.urdf`` beside the file.
    record : dict
        Source, window, sample period, tau_f, Newey-West lag.
    coulomb_width : list of float or None
        Per joint, the widths ``v_j`` of ``fc_j tanh(qd_j / v_j)`` the base parameters were
        identified with [rad/s] (``identify --coulomb-width profile``: one per joint; None in files
        written before it: ``friction_velocity`` for every joint). :meth:`predict` uses them.
    identity : dict or None
        :func:`arm_identity` of the arm identified on (None in files written before it).
    torque_offset : list of float or None
        Per joint, the constant torque offset of each channel fitted with the parameters
        (``identify --torque-offset``) [N m]; :meth:`predict` adds it. None: none fitted.

    Examples
    --------
    What ``identify --out`` writes, from a weighted least squares of a record (here the
    vertical three-joint arm's URDF torques along a sine, so the fit gives the URDF back):

    >>> import numpy as np
    >>> from adaptive_dd.identification.identified_model import IdentifiedModel
    >>> from adaptive_dd.identification.log_fit import fit_log, predict_torque
    >>> from adaptive_dd.identification.model import arm_model
    >>> from adaptive_dd.plant import Arm
    >>> from adaptive_dd.robots import robot_urdf
    >>> arm = Arm.from_urdf(robot_urdf("vertical3"))
    >>> model = arm_model(arm)
    >>> T = 1e-3
    >>> t = np.arange(0.0, 3.0, T)[:, None]
    >>> q = 0.8 * np.sin([1.1, 1.7, 2.3] * t) + 0.4 * np.sin([3.1, 4.3, 5.9] * t)
    >>> qd = np.gradient(q, T, axis=0)
    >>> qdd = np.gradient(qd, T, axis=0)
    >>> tau = predict_torque(model, arm.sigma, q, qd, qdd)  # [N m]
    >>> fit = fit_log(model, q, qd, tau, np.ones(3, bool), np.ones(model.p, bool),
    ...               tau_f=0.01, sample_period=T)
    >>> m = IdentifiedModel(
    ...     urdf=str(arm.urdf), payload_frame=arm.payload_frame, gravity=arm.gravity.tolist(),
    ...     repair_inertia=False, joint_names=list(arm.joint_names),
    ...     friction_velocity=float(model.friction_velocity), names=list(model.names),
    ...     sigma=fit.sigma.tolist(), sigma_urdf=model.sigma_ref.tolist(), std=fit.std.tolist(),
    ...     identified=fit.identified.tolist(), covariance=fit.cov.tolist(),
    ...     used=fit.used.tolist(), residual_rms=fit.residual_rms.tolist(),
    ...     noise_rms=fit.noise_rms.tolist(), viscous=arm.viscous.tolist(),
    ...     coulomb=arm.coulomb.tolist(), armature=arm.armature.tolist(),
    ...     consistent_sigma=None, consistent_distance=None, fitted_urdf=None,
    ...     record={"source": "sine", "sample_period": T, "tau_f": 0.01})
    >>> m.names[0]  # a base parameter: a combination of the links' standard parameters
    'mx1 + 0.4*m2 + 0.4*m3'
    >>> err = np.abs(m.predict(q, qd, qdd) - tau).max(axis=0)  # its torques against the record's [N m]
    >>> bool(np.all(err < 0.01 * np.abs(tau).max(axis=0)))
    True
    """

    urdf: str
    payload_frame: str
    gravity: list
    repair_inertia: bool
    joint_names: list
    friction_velocity: float
    names: list
    sigma: list
    sigma_urdf: list
    std: list
    identified: list
    covariance: list
    used: list
    residual_rms: list
    noise_rms: list
    viscous: list
    coulomb: list
    armature: list
    consistent_sigma: list | None
    consistent_distance: float | None
    fitted_urdf: str | None
    record: dict
    coulomb_width: list | None = None
    identity: dict | None = None
    torque_offset: list | None = None

    def arm(self, fitted: bool = False):
        """The :class:`~adaptive_dd.plant.arm.Arm` (``fitted``: from ``model.urdf``)."""
        from adaptive_dd.plant.arm import Arm

        if fitted and self.fitted_urdf is None:
            raise DataError("this model has no fitted URDF (no physically consistent fit was found)")
        path = self.fitted_urdf if fitted else self.urdf
        return Arm.from_urdf(
            path,
            self.payload_frame,
            gravity=self.gravity,
            repair_inertia=self.repair_inertia and not fitted,
            viscous=np.asarray(self.viscous),
            coulomb=np.asarray(self.coulomb),
            armature=np.asarray(self.armature),
            friction_velocity=self.friction_velocity,
        )

    def predict(self, q, qd, qdd, model=None) -> Array:
        """Joint torques ``(N, n)`` [N m] of the identified base parameters (and the channels' torque
        offsets, when fitted: what the record's torque channels read)."""
        from adaptive_dd.identification.log_fit import predict_torque

        tau = predict_torque(model or self.arm_model(), np.asarray(self.sigma), q, qd, qdd)
        if self.torque_offset is not None:
            tau = tau + np.asarray(self.torque_offset, dtype=float)
        return tau

    def arm_model(self, arm=None):
        """The :class:`~adaptive_dd.identification.model.Model` of :meth:`arm` (or of ``arm``, the
        same arm by :func:`arm_identity`, e.g. from a copy of the URDF), checked against the stored
        base parameter names."""
        import dataclasses

        from adaptive_dd.identification.model import arm_model

        model = arm_model(self.arm() if arm is None else arm)
        if list(model.names) != list(self.names):
            raise DataError(
                f"{self.urdf}: its base parameters ({model.p}) are not those of the model file "
                f"({len(self.names)}): the URDF changed since the identification"
            )
        width = np.asarray(
            self.coulomb_width if self.coulomb_width is not None else [self.friction_velocity], dtype=float
        )
        if np.all(width == model.friction_velocity):
            return model  # one width for every joint: the arm's, a float
        if np.all(width == width[0]):
            return dataclasses.replace(model, friction_velocity=float(width[0]))
        return dataclasses.replace(model, friction_velocity=width)


def _numbers(a) -> str:
    """Numbers as text: 10 significant digits of values rounded to 1e-10 (the round-off of a
    product that should be 0, 1e-16, is 0)."""
    return ",".join(f"{x:.10g}" for x in np.round(np.asarray(a, dtype=float).ravel(), 10) + 0.0)


def arm_identity(arm, model, identified) -> dict:
    """What names an arm by content (module docstring): ``{"hash", "kinematics", "fixed"}``.

    ``kinematics`` lists per joint its name, type, axis and placement (rotation, translation) and
    the gravity and payload frame; ``fixed`` maps each base parameter the identification held
    (``identified`` False) to the URDF's value. The hash is SHA-256 of both, numbers printed to 10
    significant digits (a copy of the URDF, or the same URDF re-read, gives the same hash).
    """
    import hashlib

    c = model.chain
    joints = [
        {
            "name": str(nm),
            "type": "prismatic" if int(c.jtype[j]) == 1 else "revolute",
            "axis": _numbers(c.axis[j]),
            "rotation": _numbers(c.rot[j]),
            "translation": _numbers(c.trans[j]),
        }
        for j, nm in enumerate(arm.joint_names)
    ]
    kin = {"joints": joints, "gravity": _numbers(c.gravity), "payload_frame": str(arm.payload_frame)}
    K = np.asarray(identified, dtype=bool)
    fixed = {
        str(nm): float(_numbers(v)) for nm, v, k in zip(model.names, model.sigma_ref, K, strict=True) if not k
    }
    text = json.dumps({"kinematics": kin, "fixed": fixed}, sort_keys=True)
    return {"hash": hashlib.sha256(text.encode()).hexdigest(), "kinematics": kin, "fixed": fixed}


def identity_differences(a: dict, b: dict) -> list[str]:
    """What differs between two :func:`arm_identity` (``a`` the model's, ``b`` the other arm's),
    one line each (empty: the same arm)."""
    if a["hash"] == b["hash"]:
        return []
    out = []
    ka, kb = a["kinematics"], b["kinematics"]
    na, nb = [j["name"] for j in ka["joints"]], [j["name"] for j in kb["joints"]]
    if na != nb:
        out.append(f"joints: {na} against {nb}")
    else:
        for ja, jb in zip(ka["joints"], kb["joints"], strict=True):
            for key in ("type", "axis", "rotation", "translation"):
                if ja[key] != jb[key]:
                    out.append(f"joint '{ja['name']}' {key}: {ja[key]} against {jb[key]}")
    for key in ("gravity", "payload_frame"):
        if ka[key] != kb[key]:
            out.append(f"{key}: {ka[key]} against {kb[key]}")
    fa, fb = a["fixed"], b["fixed"]
    for nm in sorted(set(fa) | set(fb)):
        if fa.get(nm) != fb.get(nm):
            out.append(f"fixed parameter {nm}: {fa.get(nm)} against {fb.get(nm)}")
    return out or ["the hashes differ"]


def save_identified_model(path, model: IdentifiedModel) -> Path:
    """Write ``model`` as JSON (NaN as null).

    Parameters
    ----------
    path : str or Path
        The JSON file to write.
    model : IdentifiedModel
        What ``adaptive-dd identify`` found.

    Returns
    -------
    Path
        The file written.

    Examples
    --------
    The UR5's URDF as a model file (its own base parameters, none identified), written and
    read back:

    >>> import tempfile
    >>> import numpy as np
    >>> from adaptive_dd.identification.identified_model import (
    ...     IdentifiedModel, load_identified_model, save_identified_model)
    >>> from adaptive_dd.identification.model import arm_model
    >>> from adaptive_dd.plant import Arm
    >>> from adaptive_dd.robots import robot_urdf
    >>> arm = Arm.from_urdf(robot_urdf("ur5"))
    >>> model = arm_model(arm)
    >>> n, p = arm.n_joints, model.p
    >>> m = IdentifiedModel(
    ...     urdf=str(arm.urdf), payload_frame=arm.payload_frame, gravity=arm.gravity.tolist(),
    ...     repair_inertia=False, joint_names=list(arm.joint_names),
    ...     friction_velocity=float(model.friction_velocity), names=list(model.names),
    ...     sigma=model.sigma_ref.tolist(), sigma_urdf=model.sigma_ref.tolist(), std=[0.0] * p,
    ...     identified=[False] * p, covariance=np.zeros((p, p)).tolist(), used=[True] * n,
    ...     residual_rms=[float("nan")] * n, noise_rms=[float("nan")] * n,
    ...     viscous=arm.viscous.tolist(), coulomb=arm.coulomb.tolist(),
    ...     armature=arm.armature.tolist(), consistent_sigma=None, consistent_distance=None,
    ...     fitted_urdf=None, record={"source": "the URDF"})
    >>> path = save_identified_model(f"{tempfile.mkdtemp()}/model.json", m)
    >>> back = load_identified_model(path)
    >>> back.sigma == m.sigma, back.residual_rms[0]  # NaN is written as null and read back
    (True, nan)
    """
    from adaptive_dd.outputs import atomic_write

    def clean(x):
        if isinstance(x, float) and not np.isfinite(x):
            return None
        if isinstance(x, list):
            return [clean(v) for v in x]
        if isinstance(x, dict):
            return {k: clean(v) for k, v in x.items()}
        return x

    path = Path(path)
    with atomic_write(path, encoding="utf-8") as fh:
        json.dump({"format": FORMAT, **clean(asdict(model))}, fh, indent=1)
    return path


def load_identified_model(path, need_urdf: bool = True) -> IdentifiedModel:
    """Read a ``model.json`` written by ``adaptive-dd identify --out``.


    Parameters
    ----------
    path : str or Path
        A ``model.json``.

    Returns
    -------
    IdentifiedModel
        The model, checked against the URDF it names.


    Examples
    --------
    >>> from adaptive_dd.identification.identified_model import load_identified_model
    >>> load_identified_model("results/none/model.json")
    Traceback (most recent call last):
    ...
    adaptive_dd.errors.DataError: results/none/model.json: no such model file (written by ...)

    Raises
    ------
    DataError
        Naming the file and the key: not JSON, another format, a missing key, lengths that
        do not agree, a URDF that is gone (``need_urdf``; False: the caller brings the arm, checked
        by :func:`arm_identity`).
    """
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: no such model file (written by adaptive-dd identify --out DIR)")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise DataError(f"{path}: not a JSON model file: {exc}") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise DataError(f"{path}: key 'format' is not {FORMAT!r}: not a model written by identify --out")
    fields = IdentifiedModel.__dataclass_fields__
    optional = ("coulomb_width", "identity", "torque_offset")  # absent from files written before them
    missing = [k for k in fields if k not in data and k not in optional]
    if missing:
        raise DataError(f"{path}: missing key(s) {missing}")

    def nan(x):
        return [np.nan if v is None else v for v in x]

    kw = {k: data[k] for k in fields if k in data}
    for k in ("residual_rms", "noise_rms"):
        kw[k] = nan(kw[k])
    p, n = len(kw["names"]), len(kw["joint_names"])
    for k in ("sigma", "sigma_urdf", "std", "identified"):
        if len(kw[k]) != p:
            raise DataError(f"{path}: key '{k}' has {len(kw[k])} entries, 'names' {p}")
    for k in ("sigma", "sigma_urdf", "viscous", "coulomb", "armature"):
        bad = [v for v in kw[k] if not (is_finite_number(v) and abs(v) < 1e12)]
        if bad:
            raise DataError(f"{path}: key '{k}' must hold finite numbers (|x| < 1e12), got {bad[0]!r}")
    if np.shape(kw["covariance"]) != (p, p):
        raise DataError(f"{path}: key 'covariance' must be {p} x {p}")
    width = kw.get("coulomb_width")
    if width is not None and (
        len(width) != n or not all(isinstance(v, (int, float)) and 0 < v < float("inf") for v in width)
    ):
        raise DataError(f"{path}: key 'coulomb_width' must be {n} widths > 0 [rad/s], got {width!r}")
    offset = kw.get("torque_offset")
    if offset is not None and (
        len(offset) != n or not all(isinstance(v, (int, float)) and np.isfinite(v) for v in offset)
    ):
        raise DataError(f"{path}: key 'torque_offset' must be {n} finite offsets [N m], got {offset!r}")
    for k in ("used", "residual_rms", "noise_rms", "viscous", "coulomb", "armature"):
        if len(kw[k]) != n:
            raise DataError(f"{path}: key '{k}' has {len(kw[k])} entries, 'joint_names' {n}")
    for k in ("urdf", "fitted_urdf"):
        if kw[k] is not None:
            u = Path(kw[k])
            u = u if u.is_absolute() else path.parent / u
            if not u.is_file() and need_urdf:
                raise DataError(f"{path}: key '{k}': the URDF {u} is not there")
            kw[k] = str(u)
    return IdentifiedModel(**kw)
