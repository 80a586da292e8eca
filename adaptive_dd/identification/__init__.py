"""Identification of sigma: derivative filters (M1, M2), filtered regressions, RLS (eq. 14),
batch least squares, a filterpy Kalman estimator, the reproduction of Tables 3 and 5, and
against the information limit: output sensitivities, Fisher information and Cramér-Rao
bounds, output-error (maximum-likelihood) estimation and an augmented-state EKF."""

# Each name is imported from its module on first use (PEP 562): importing one submodule, e.g.
# the online estimator for a benchmark, does not import the rest (the output-error fit's SciPy
# optimizers alone are about 0.5 s of a warm run's start).
_LAZY = {
    "AKFConfig": "adaptive_dd.identification.augmented_kf",
    "AKFState": "adaptive_dd.identification.augmented_kf",
    "AugmentedKalmanFilter": "adaptive_dd.identification.augmented_kf",
    "ESTIMATORS": "adaptive_dd.identification.estimators",
    "EXACT_RLS": "adaptive_dd.identification.estimators",
    "EstimationResult": "adaptive_dd.identification.estimators",
    "FilterBank": "adaptive_dd.identification.filters",
    "FilteredRegression": "adaptive_dd.identification.regressors",
    "FisherResult": "adaptive_dd.identification.fisher",
    "KalmanParameterEstimator": "adaptive_dd.identification.kalman",
    "OnlineRegressor": "adaptive_dd.identification.regressors",
    "PAPER_RLS": "adaptive_dd.identification.estimators",
    "RLSConfig": "adaptive_dd.identification.rls",
    "RLSState": "adaptive_dd.identification.rls",
    "RecursiveLeastSquares": "adaptive_dd.identification.rls",
    "SPLITS": "adaptive_dd.identification.estimators",
    "SplitRLS": "adaptive_dd.identification.estimators",
    "StreamingFilter": "adaptive_dd.identification.filters",
    "TwoLinkOutputErrorResult": "adaptive_dd.identification.two_link_output_error",
    "akf_init": "adaptive_dd.identification.augmented_kf",
    "akf_predict": "adaptive_dd.identification.augmented_kf",
    "akf_step": "adaptive_dd.identification.augmented_kf",
    "akf_update": "adaptive_dd.identification.augmented_kf",
    "align_torque": "adaptive_dd.identification.estimators",
    "batch_least_squares": "adaptive_dd.identification.rls",
    "chain_sensitivities": "adaptive_dd.identification.sensitivity",
    "crb_from_fisher": "adaptive_dd.identification.fisher",
    "design_filter_bank": "adaptive_dd.identification.filters",
    "estimate": "adaptive_dd.identification.estimators",
    "excitation_mask": "adaptive_dd.identification.estimators",
    "filter_record": "adaptive_dd.identification.filters",
    "filter_step": "adaptive_dd.identification.filters",
    "finite_difference_sensitivities": "adaptive_dd.identification.sensitivity",
    "fisher_from_sensitivities": "adaptive_dd.identification.fisher",
    "fisher_information": "adaptive_dd.identification.fisher",
    "linear_gaussian_crb": "adaptive_dd.identification.fisher",
    "local_sensitivities": "adaptive_dd.identification.sensitivity",
    "mass_information_time": "adaptive_dd.identification.fisher",
    "output_error_fit": "adaptive_dd.identification.two_link_output_error",
    "prepare_regression": "adaptive_dd.identification.estimators",
    "rls_init": "adaptive_dd.identification.rls",
    "rls_step": "adaptive_dd.identification.rls",
    "simulate_trajectory": "adaptive_dd.identification.sensitivity",
    "solve_regression": "adaptive_dd.identification.estimators",
    "two_link_filtered_regression": "adaptive_dd.identification.regressors",
}


def __getattr__(name: str):
    mod = _LAZY.get(name)
    if mod is None:
        raise AttributeError(f"module 'adaptive_dd.identification' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(mod), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


__all__ = sorted(_LAZY)
