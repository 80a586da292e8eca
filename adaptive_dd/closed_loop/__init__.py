"""The closed loop for any serial arm (:class:`~adaptive_dd.plant.arm.Arm`).

Layout (data first, then arithmetic, then drivers):

:mod:`~adaptive_dd.closed_loop.types`
    NamedTuples of arrays that travel into the compiled kernels (run constants, actuator
    and sensor, plant, per-trial state, streamed sums, recordings, law configuration).
:mod:`~adaptive_dd.closed_loop.laws`
    The one compiled law kernel of the computed-torque family (PD, computed torque with a
    fixed, true or estimated model, Slotine-Li with payload adaptation).
:mod:`~adaptive_dd.closed_loop.glue`
    The per-sample glue written once for every arm (measure, guard, actuate, plant step,
    divergence, failure freeze, metrics, recording, alarms), with the plant, the law and the
    estimator as compile-time choices (the two-link arm's: :mod:`adaptive_dd.benchmark.compiled`),
    and the compiled whole-block driver.
:mod:`~adaptive_dd.closed_loop.noise`
    Sensor noise and dropouts of every trial, drawn block by block (both arms, both paths).
:mod:`~adaptive_dd.closed_loop.python_path`
    The Python path (a controller object's ``reset / command / observe``) written once for
    both arms, around each arm's batch glue.
:mod:`~adaptive_dd.closed_loop.controllers`
    One class per built-in controller, owning its Python ``command`` and its compiled form;
    :data:`~adaptive_dd.closed_loop.controllers.ARM_CONTROLLERS` (name -> class), built by
    :func:`adaptive_dd.controllers.make_controller` like every controller on every arm.
:mod:`~adaptive_dd.closed_loop.runner`
    :func:`~adaptive_dd.closed_loop.runner.run_closed_loop`: every controller over every seed.
"""

from adaptive_dd.closed_loop.controllers import ARM_CONTROLLERS
from adaptive_dd.closed_loop.runner import run_closed_loop

__all__ = ["ARM_CONTROLLERS", "run_closed_loop"]
