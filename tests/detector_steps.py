"""One sample of the N-joint detector as the estimator's kernel takes it, shared by the detector tests."""

from __future__ import annotations

from adaptive_dd.identification import online_kernel as K


def detector_sample(c, s, eps, act) -> bool:
    """``online_detector._detect`` on trial 0's rows ``eps`` (those in use: ``act``), then what the
    kernel does after it: an alarm (``_alarm``) or one more sample since the last, and the sample
    count. Whether it alarmed."""
    alarmed = bool(K._detect(c, s, 0, eps, act))
    if alarmed:
        K._alarm(c, s, 0, s.cnt[0, K.C_K])
    else:
        s.cnt[0, K.C_SINCE_ALARM] += 1
    s.cnt[0, K.C_K] += 1
    return alarmed
