"""Identification of sigma: derivative filters (M1, M2), filtered regressions, RLS (eq. 14),
batch least squares, a filterpy Kalman estimator, the reproduction of Tables 3 and 5, and
against the information limit: output sensitivities, Fisher information and Cramér-Rao
bounds, output-error (maximum-likelihood) estimation and an augmented-state EKF."""

from adaptive_dd.identification.augmented_kf import (
    AKFConfig,
    AKFState,
    AugmentedKalmanFilter,
    akf_init,
    akf_predict,
    akf_step,
    akf_update,
)
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
from adaptive_dd.identification.fisher import (
    FisherResult,
    crb_from_fisher,
    fisher_from_sensitivities,
    fisher_information,
    linear_gaussian_crb,
    mass_information_time,
)
from adaptive_dd.identification.kalman import KalmanParameterEstimator
from adaptive_dd.identification.regressors import (
    FilteredRegression,
    OnlineRegressor,
    two_link_filtered_regression,
)
from adaptive_dd.identification.rls import (
    RecursiveLeastSquares,
    RLSConfig,
    RLSState,
    batch_least_squares,
    rls_init,
    rls_step,
)
from adaptive_dd.identification.sensitivity import (
    chain_sensitivities,
    finite_difference_sensitivities,
    local_sensitivities,
    simulate_trajectory,
)
from adaptive_dd.identification.two_link_output_error import TwoLinkOutputErrorResult, output_error_fit

__all__ = [
    "ESTIMATORS",
    "EXACT_RLS",
    "PAPER_RLS",
    "SPLITS",
    "AKFConfig",
    "AKFState",
    "AugmentedKalmanFilter",
    "EstimationResult",
    "FilterBank",
    "FilteredRegression",
    "FisherResult",
    "KalmanParameterEstimator",
    "OnlineRegressor",
    "RLSConfig",
    "RLSState",
    "RecursiveLeastSquares",
    "SplitRLS",
    "StreamingFilter",
    "TwoLinkOutputErrorResult",
    "akf_init",
    "akf_predict",
    "akf_step",
    "akf_update",
    "align_torque",
    "batch_least_squares",
    "chain_sensitivities",
    "crb_from_fisher",
    "design_filter_bank",
    "estimate",
    "excitation_mask",
    "filter_record",
    "filter_step",
    "finite_difference_sensitivities",
    "fisher_from_sensitivities",
    "fisher_information",
    "linear_gaussian_crb",
    "local_sensitivities",
    "mass_information_time",
    "output_error_fit",
    "prepare_regression",
    "rls_init",
    "rls_step",
    "simulate_trajectory",
    "solve_regression",
    "two_link_filtered_regression",
]
