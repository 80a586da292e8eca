"""The closed loop's per-sample kernels are compiled without numba's reference counting.

Each call of a compiled function that takes records of arrays (the chain, the law's
configuration, the scratch) updates the reference count of every array it unpacks: in the N-joint
loop, whose records are borrowed, each update is a call on a null pointer, and they were 8-9 % of
a sample of the paper's arm on the general kernels (``benchmarks/profile_loop.py``). Compiled with
``_nrt=False`` these kernels make no such call; numba compiles what they call with the same flag,
so none of them may allocate (an allocation fails their compilation) or return an array (none
does: every scratch array comes in from the caller).
"""

from __future__ import annotations

import pytest

from adaptive_dd.closed_loop import laws, residual_observer
from adaptive_dd.controllers import kernels
from adaptive_dd.identification import online_kernel
from adaptive_dd.plant import chain_rk4

PER_SAMPLE = [
    (online_kernel, "est_step_model"),
    (chain_rk4, "_stick_slip"),
    (chain_rk4, "_smooth"),
    (chain_rk4, "_lugre"),
    (chain_rk4, "_rk4"),
    (chain_rk4, "_decide"),
    (chain_rk4, "_resolve"),
    (chain_rk4, "_consistent"),
    (laws, "_model_torque"),
    (laws, "_add_nominal_inertia"),
    (laws, "_sliding_term"),
    (laws, "_adapt_payload"),
    (laws, "_boost_within_limits"),
    (residual_observer, "_momentum"),
    (residual_observer, "_observe"),
    (kernels, "reference_torque"),  # a plug-in's, as the built-ins'
    (kernels, "payload_regressor"),
]


@pytest.mark.parametrize(("module", "name"), PER_SAMPLE, ids=[n for _, n in PER_SAMPLE])
def test_per_sample_kernels_are_compiled_without_reference_counts(module, name):
    kernel = getattr(module, name)
    assert kernel.targetoptions.get("_nrt") is False, (
        f"{module.__name__}.{name} is compiled with reference counting: a call per array it "
        "unpacks, every sample"
    )
