"""The slots of the two-link online estimator's flat state and configuration arrays
(:mod:`adaptive_dd.identification.two_link_online_kernel`): ``ci`` integer and ``cf`` float
settings, the detector's short-window state ``S_*`` with its GLR candidates ``G_*``, the
counters ``C_*``."""

from __future__ import annotations

# integer slots of ci
I_CONSTRUCTION = 0  # 0 paper, 1 exact
I_SPLIT = 1  # 0 full, 1 "15", 2 "16"
I_ALIGN = 2
I_SELECT = 3  # data selection on/off
I_SEL_MEMORY = 4  # samples
I_TAINT = 5  # samples a non-finite input taints the filtered equations
I_DETECT = 6
I_WARMUP = 7  # samples
I_MIN_LEARNED = 8
I_HOLDOFF = 9
I_RESUME = 10
I_FREEZE = 11
I_REOPEN_AGAIN = 12
I_PROJECT = 13  # 0 none, 1 the control model only, 2 the estimator state too
I_PERSIST_MIN = 14  # samples the persistence test needs since it restarted
I_GLR_SPACING = 15  # samples between the onsets of two GLR candidates
I_GLR_MIN_AGE = 16  # samples a candidate must have run before it may alarm
I_SPEED_MEMORY = 17  # samples a joint must have been faster than F_DET_SPEED
N_CI = 18

# float slots of cf
F_LAM0 = 0
F_MU = 1
F_CAP0 = 2  # trace cap of the covariance block of group 0 (F_CAP1: group 1); <= 0: none
F_SEL_THRESHOLD = 3
F_ALPHA_SHORT = 4
F_ALPHA_LONG = 5
F_THRESHOLD2 = 6
F_P_MASS = 7
F_P_J2 = 8
F_J_MIN = 9
F_MARGIN = 10
F_R_MIN = 11
F_CAP1 = 12
# 13: unused
F_ALPHA_DIR = 14  # EWMA weight of the payload-direction test (short window)
F_ALPHA_PERSIST = 15  # EWMA weight of the persistence test
F_MIN_MASS = 16  # [kg] smallest payload change an alarm may claim
F_MIN_EXPLAINED = 17  # fraction of the weighted error energy the payload direction must explain
F_GLR_THRESHOLD = 18  # threshold on A^2 / B of a GLR candidate
F_HETERO = 19  # a candidate's score is A^2 / B - heterogeneity / F_HETERO
F_DET_SPEED = 20  # [rad/s] an equation feeds the payload tests only while its joint is faster
F_REMOVAL = 21  # a GLR alarm may claim removing at most this many times the mass carried (+ min_mass)
N_CF = 22
F_XS0 = N_CF  # cf[F_XS0:]: the filters' state under a unit constant input, (I - A)^-1 B (order,)

# columns of the detector statistics `short` (n, N_SHORT)
S_E2 = 0  # 0, 1: short average of the squared prior error per equation
S_DIR = 2  # 2, 3, 4: short averages of sum_j w_j phi_d,j e_j, w_j phi_d,j^2, w_j e_j^2
S_PER = 5  # 5, 6, 7: the same over the persistence window (restarted at each alarm)
S_PER_N = 8  # samples in the persistence window
S_LREF = 9  # 9, 10: last long-run level per equation that was learned in full (the weights w_j)
S_M0 = 11  # d . theta0 / (d . d) of the start estimate (the arm without payload): the mass origin
S_GLR = 12  # GLR candidates, GLR_STRIDE columns each (see _glr_update)
GLR_CANDIDATES = 16
GLR_CHANNELS = 5  # exact-construction channels of the inertial columns (J1, J2, r)
G_X = 0  # filter state, GLR_CHANNELS x 2
G_OFF = 10  # channel values at the onset (channels 0..3, those filtered by G1)
G_A = 14  # per equation j: sum of w_j psi_j e_j (G_A + j), w_j psi_j^2 (G_A + 2 + j)
G_E = 18  # sum of w_j e_j^2 over both equations
G_AGE = 19
GLR_STRIDE = 20
N_SHORT = S_GLR + GLR_CANDIDATES * GLR_STRIDE

# columns of the per-trial integer state `cnt`
C_STARTED = 0
C_SINCE_BAD = 1
C_SINCE_SLOW1 = 2
C_SINCE_SLOW2 = 3
C_SKIPPED = 4
C_LEARNED1 = 5
C_LEARNED2 = 6
C_SINCE_ALARM = 7
C_REOPEN_AT = 8
C_ALARMS = 9
C_K = 10
C_SINCE_SLOW_DET1 = 11  # samples since joint 1 was slower than the detector's speed (12: joint 2)
N_CNT = 13

BIG = 1 << 40
