"""The curated API reference: the objects a user needs, grouped by task.

One list, read by ``apigen`` (which writes ``docs/api/index.rst`` and one page per object) and
by ``tests/test_doctests.py`` (which checks each object's numpydoc sections and runs its
``Examples`` as doctests). Each entry is the dotted name of the object where it is defined,
except where a shorter public path is how users import it (``adaptive_dd.Simulation``): the
page is then under that path. Everything else in the package is an internal: importable, with
its docstring, but not part of the reference's index.
"""

from __future__ import annotations

#: (section title, one sentence on the task, dotted names)
GROUPS: list[tuple[str, str, list[str]]] = [
    (
        "Run the benchmark",
        "Load a scenario, run every controller on every seed, read the per-seed ratios to the floor.",
        [
            "adaptive_dd.benchmark.scenario.load_scenario",
            "adaptive_dd.benchmark.scenario.parse_scenario",
            "adaptive_dd.benchmark.scenario.default_scenario_path",
            "adaptive_dd.benchmark.scenario.Scenario",
            "adaptive_dd.benchmark.scenario.run_estimate",
            "adaptive_dd.benchmark.runner.run_benchmark",
            "adaptive_dd.benchmark.types.BenchmarkResult",
            "adaptive_dd.benchmark.types.ControllerRun",
            "adaptive_dd.benchmark.results.frame_columns",
        ],
    ),
    (
        "Step an arm from your own loop",
        "One trial of a scenario, sample by sample, with your own torque; or one controller on one seed.",
        [
            "adaptive_dd.simulation.Simulation",
            "adaptive_dd.simulation.Measurement",
            "adaptive_dd.simulation.run_trial",
        ],
    ),
    (
        "Arms, robots and payloads",
        "An arm from a URDF or the paper's tables, the shipped robots, a payload's parameters.",
        [
            "adaptive_dd.plant.arm.Arm",
            "adaptive_dd.robots.robot_urdf",
            "adaptive_dd.robots.RobotInfo",
            "adaptive_dd.plant.payload.payload_parameters",
            "adaptive_dd.plant.payload.PayloadEstimate",
            "adaptive_dd.plant.two_link.ClosedFormTwoLink",
        ],
    ),
    (
        "Controllers",
        "Build a built-in controller by name, list them, or write your own against the protocol.",
        [
            "adaptive_dd.controllers.registry.make_controller",
            "adaptive_dd.controllers.registry.controllers_for",
            "adaptive_dd.controllers.registry.gains_for",
            "adaptive_dd.controllers.registry.inventory",
            "adaptive_dd.controllers.base.Controller",
            "adaptive_dd.controllers.base.Gains",
            "adaptive_dd.controllers.feedback.PD",
            "adaptive_dd.controllers.feedback.ComputedTorque",
            "adaptive_dd.controllers.adaptive.AdaptiveCT",
            "adaptive_dd.controllers.slotine_li.SlotineLi",
        ],
    ),
    (
        "Identify an arm from a record",
        "Simulated or logged records, least squares with its covariance, output error and its "
        "Cramér-Rao bound, excitation design, the model file the benchmark reads.",
        [
            "adaptive_dd.identification.records.simulate_record",
            "adaptive_dd.identification.records.Record",
            "adaptive_dd.record.read_log",
            "adaptive_dd.record.record_spec",
            "adaptive_dd.identification.log_fit.fit_log",
            "adaptive_dd.identification.log_fit.LogFit",
            "adaptive_dd.identification.log_fit.predict_torque",
            "adaptive_dd.identification.output_error.fit_output_error",
            "adaptive_dd.identification.output_error.OutputErrorResult",
            "adaptive_dd.identification.excitation.design_excitation",
            "adaptive_dd.identification.identified_model.IdentifiedModel",
            "adaptive_dd.identification.identified_model.load_identified_model",
            "adaptive_dd.identification.identified_model.save_identified_model",
            "adaptive_dd.identification.payload_pair.payload_from_pair",
            "adaptive_dd.identification.payload_pair.PayloadResult",
        ],
    ),
    (
        "Estimate online",
        "The recursive estimators inside adaptive_ct, on arrays with the trial axis first.",
        [
            "adaptive_dd.identification.rls.rls_init",
            "adaptive_dd.identification.rls.rls_step",
            "adaptive_dd.identification.rls.batch_least_squares",
            "adaptive_dd.identification.rls.RLSConfig",
            "adaptive_dd.identification.filters.design_filter_bank",
            "adaptive_dd.identification.two_link_online.online_init",
            "adaptive_dd.identification.two_link_online.online_step",
            "adaptive_dd.identification.two_link_online.run_two_link_online",
            "adaptive_dd.identification.two_link_online_config.TwoLinkOnlineConfig",
            "adaptive_dd.identification.online.OnlineConfig",
            "adaptive_dd.identification.online.Detector",
        ],
    ),
    (
        "What the sensors allow",
        "Information limits: the time an efficient estimator or an optimal test needs.",
        [
            "adaptive_dd.identification.payload_information.payload_information_time",
            "adaptive_dd.identification.detection_limit.detection_limit",
        ],
    ),
    (
        "Sweeps",
        "Grids over scenario fields x controllers x seeds, on a local or remote Dask cluster.",
        [
            "adaptive_dd.sweep_spec.load_sweep",
            "adaptive_dd.sweep_spec.parse_sweep",
            "adaptive_dd.sweep.run_sweep",
            "adaptive_dd.sweep.SweepResult",
            "adaptive_dd.sweep.ratio_medians",
        ],
    ),
    (
        "Plots",
        "matplotlib figures of a result, with units on every axis; none of them shows a window.",
        [
            "adaptive_dd.plotting.plot_tracking_errors",
            "adaptive_dd.plotting.plot_ratios",
            "adaptive_dd.plotting.plot_joint_errors",
            "adaptive_dd.plotting.plot_estimates",
            "adaptive_dd.plotting.plot_payload_estimates",
            "adaptive_dd.plotting.plot_benchmark_estimates",
            "adaptive_dd.plotting.plot_trajectory",
            "adaptive_dd.plotting.plot_model_response",
            "adaptive_dd.plotting.save_figure",
            "adaptive_dd.identification_plots.plot_torque_fit",
            "adaptive_dd.sweep_plot.plot_ratio_heatmaps",
        ],
    ),
    (
        "Reproduce the paper",
        "Tables 3 and 5 of the paper, with its values beside ours.",
        [
            "adaptive_dd.identification.reproduce.run_reproduce",
            "adaptive_dd.identification.reproduce.paper_comparison",
        ],
    ),
    (
        "Arms nobody tuned for, other contenders, learned policies",
        "Draw a population of arms, rank every controller against its floor, run a policy through "
        "the Gymnasium environment.",
        [
            "adaptive_dd.robots.random_arm.random_arm",
            "adaptive_dd.arena.leaderboard.leaderboard",
            "adaptive_dd.gym.make_env",
            "adaptive_dd.gym.env.PayloadSwapEnv",
            "adaptive_dd.gym.score.evaluate",
        ],
    ),
    (
        "Errors",
        "Every error the package raises on bad input; each names what was wrong and where.",
        [
            "adaptive_dd.errors.ScenarioError",
            "adaptive_dd.errors.ParameterError",
            "adaptive_dd.errors.SignalError",
            "adaptive_dd.errors.DataError",
            "adaptive_dd.errors.OutputError",
            "adaptive_dd.errors.UrdfError",
            "adaptive_dd.sweep_spec.SweepError",
            "adaptive_dd.robots.UnknownRobotError",
        ],
    ),
]


def listed() -> list[str]:
    """Every curated dotted name, in the reference's order."""
    return [name for _, _, names in GROUPS for name in names]
