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
F_T = 13  # [s] the sample period (the momentum test's increments)
F_ALPHA_DIR = 14  # EWMA weight of the payload-direction test (short window)
F_ALPHA_PERSIST = 15  # EWMA weight of the persistence test
F_MIN_MASS = 16  # [kg] smallest payload change an alarm may claim
F_MIN_EXPLAINED = 17  # fraction of the weighted error energy the payload direction must explain
F_GLR_THRESHOLD = 18  # threshold on A^2 / B of a GLR candidate
F_HETERO = 19  # a candidate's score is A^2 / B - heterogeneity / F_HETERO
F_DET_SPEED = 20  # [rad/s] an equation feeds the payload tests only while its joint is faster
F_REMOVAL = 21  # a GLR alarm may claim removing at most this many times the mass carried (+ min_mass)
F_MG_THRESHOLD = 22  # threshold on the momentum test's A^2 / B (0: no momentum test)
N_CF = 23
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
# the momentum test (two_link_momentum_test): the last sample, the learnt velocity noise, the
# best candidate's score and mass, then MG_CANDIDATES candidates of MG_STRIDE columns
S_MG_PREV = S_GLR + GLR_CANDIDATES * GLR_STRIDE  # q (2), qd (2), the torque applied over it (2), fresh
S_MG_SV = S_MG_PREV + 7  # Sigma_v: 00, 01, 11 (EWMA, not bias-corrected)
S_MG_N = S_MG_SV + 3  # samples in Sigma_v
S_MG_SCORE = S_MG_N + 1  # the best candidate's A^2 / B at this sample
S_MG_DM = S_MG_SCORE + 1  # its A / B [kg]
S_MGC = S_MG_DM + 1
MG_CANDIDATES = 16
MG_MIN_AGE = 2  # samples a candidate sums before it may alarm
MG_R = 0  # R (2): the residual summed from the onset
MG_S = 2  # S (2): the payload direction's increment summed
MG_W = 4  # sum Q_m^-1 (00, 01, 11)
MG_WS = 7  # sum Q_m^-1 S_m (2)
MG_WR = 9  # sum Q_m^-1 R_m (2)
MG_A = 11  # sum S_m^T Q_m^-1 R_m
MG_B = 12  # sum S_m^T Q_m^-1 S_m
MG_K = 13  # increments summed
MG_Q0 = 14  # Q at the onset (00, 01, 11)
MG_TAINT = 17  # per joint: 1 once the joint was slow (or a sample lost) since the onset
MG_ACTIVE = 19
MG_TH = 20  # the estimate at the onset (7)
MG_STRIDE = 27
N_SHORT = S_MGC + MG_CANDIDATES * MG_STRIDE

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
