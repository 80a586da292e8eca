"""The payload-swap tracking benchmark: scenarios, the closed loop, metrics, reports."""

from adaptive_dd.benchmark.metrics import compute_metrics
from adaptive_dd.benchmark.report import format_report, write_csv, write_json
from adaptive_dd.benchmark.runner import run_benchmark
from adaptive_dd.benchmark.scenario import Reference, Scenario, default_scenario_path, load_scenario
from adaptive_dd.benchmark.types import BenchmarkResult, ControllerRun

__all__ = [
    "BenchmarkResult",
    "ControllerRun",
    "Reference",
    "Scenario",
    "compute_metrics",
    "default_scenario_path",
    "format_report",
    "load_scenario",
    "run_benchmark",
    "write_csv",
    "write_json",
]
