"""Identification of sigma: derivative filters (M1, M2), filtered regressions, RLS (eq. 14),
batch least squares, a filterpy Kalman estimator, and the reproduction of Tables 3 and 5."""

from adaptive_dd.identification.estimators import (
    ESTIMATORS,
    EXACT_RLS,
    PAPER_RLS,
    SPLITS,
    EstimationResult,
    SplitRLS,
    align_torque,
    estimate,
    excitation_mask,
    prepare_regression,
    solve_regression,
)
from adaptive_dd.identification.filters import (
    FilterBank,
    StreamingFilter,
    design_filter_bank,
    filter_record,
    filter_step,
)
from adaptive_dd.identification.kalman import KalmanParameterEstimator
from adaptive_dd.identification.regressors import FilteredRegression, OnlineRegressor, filtered_regression
from adaptive_dd.identification.rls import (
    RecursiveLeastSquares,
    RLSConfig,
    RLSState,
    batch_least_squares,
    rls_init,
    rls_step,
)

__all__ = [
    "ESTIMATORS",
    "EXACT_RLS",
    "PAPER_RLS",
    "SPLITS",
    "EstimationResult",
    "FilterBank",
    "FilteredRegression",
    "KalmanParameterEstimator",
    "OnlineRegressor",
    "RLSConfig",
    "RLSState",
    "RecursiveLeastSquares",
    "SplitRLS",
    "StreamingFilter",
    "align_torque",
    "batch_least_squares",
    "design_filter_bank",
    "estimate",
    "excitation_mask",
    "filter_record",
    "filter_step",
    "filtered_regression",
    "prepare_regression",
    "rls_init",
    "rls_step",
    "solve_regression",
]
