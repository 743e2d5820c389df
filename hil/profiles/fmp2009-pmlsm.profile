# Paper 002: Fulford, Maggiore & Apkarian, "Control of a 5DOF Magnetically
# Levitated Positioning Stage" (IEEE T-CST 2009). Four iron-cored PMLSMs
# under a platen on linear guides. [P] printed in the paper, [D] derived,
# (ours) not given: our choice (docs/PAPER-002.md gives the reasons).
#
# Axes: this family's vertical coordinate is the AIR GAP x1 of paper 002
# (what its encoders read, larger = lower platen), named z here; X is x,
# the paper's Z is y, the rotation about X (phi) is theta_x, the rotation
# about Z (theta) is theta_y; yaw is blocked by the guides (absent).
[stage]
name = fmp2009-pmlsm
title = Paper 002: 5-DOF stage on four iron-cored PMLSMs, linear guides, 1 kHz
paper = 2
family = iron_core_pmlsm
# [P] 1 kHz controller
servo_rate_Hz = 1000
# (ours) the platen rests on its lower stops (gap 31 mm); every loop closes
# and the gap reference ramps to the nominal gap.
startup = lift_off_from_dock ready

[body]
# [P] Table I: M_y (levitated part), I_x, I_z
mass_kg = 6.9
inertia_x_kgm2 = 0.5268
inertia_y_kgm2 = 0.5268
# yaw is blocked: not used (positive for the checker)
inertia_z_kgm2 = 0.5268
# [P] Table I: the X guides carry M_x, the Z guides M_z
effective_mass_x_kg = 10.6
effective_mass_y_kg = 8.6
gravity_m_per_s2 = 9.81

[pmlsm]
# [P] Table I
slot_width_m = 12.7e-3
slot_pitch_m = 19.05e-3
pole_pitch_m = 57.15e-3
magnet_height_m = 5e-3
magnet_length_m = 50e-3
magnet_width_m = 28.58e-3
coercivity_A_per_m = 875400
turns_per_phase = 900
magnets_per_motor = 4
pole_pairs = 3
# [D] one slot per pole per phase, coil pitch = tau
winding_factor = 1
# (ours) sintered NdFeB
recoil_permeability = 1.05
# [P] Table I
radius_to_movers_m = 0.397
# (ours) the operating range's centre; [P] the stops at 18 and 31 mm
nominal_gap_m = 25e-3
min_gap_m = 18e-3
max_gap_m = 31e-3
# (ours) K_v3 as printed leaves no equilibrium below ~28 mm: docs/PAPER-002.md
vertical_attraction_scale = 0.05
# (ours) above the magnetic negative stiffness; the ratio of the paper's
# tilt ranges (14 mrad about Z, 3 mrad about X)
guide_torsion_phi_per_s2 = 1.4e4
guide_torsion_theta_per_s2 = 3.0e3

[limits]
# [P] 7 A peak (sat_7 of (17)), 5 A continuous
peak_current_A = 7
rms_current_A = 5
# (ours) +-10 V DAC into 1 A/V linear amplifiers
hardware_current_A = 10
# (ours) lift-off and landing ramp of the gap reference
landing_speed_m_per_s = 2e-3
nominal_height_m = 0

# Five internal-model regulators (14)-(16), omega0 = 1.5 pi rad/s [P], LQR
# gains from Q = h'h, R = 1 (lqr_weight_h: derived from the paper's printed
# closed-loop poles, maglev-lqr-design; the paper's own weights are not
# printed). Derivative estimates by a first-order filter on the error at
# 50 Hz (ours, docs/PAPER-002.md 4). Anti-windup (17) on X and Z, E = 7e-5 [P].
# Travel: the operating range (1) of Section IV-A.
[axis z]
mode = active
travel = 0.020 0.030
max_velocity = 0.01
max_acceleration = 0.5
controller = internal_model
feedback_linearization = on
imr_omega0_rad_per_s = 4.71238898038469
antiwindup_gain = 0
derivative_filter_Hz = 50
lqr_weight_h = 1652.798431 173.2030081 49763.17211 -2081.846484 7793.325695

[axis x]
mode = active
travel = -0.030 0.030
max_velocity = 0.05
max_acceleration = 0.5
controller = internal_model
feedback_linearization = on
imr_omega0_rad_per_s = 4.71238898038469
antiwindup_gain = 7e-5
derivative_filter_Hz = 50
lqr_weight_h = 459.119941 38.73045726 21246.3488 2231.369139 2701.787843

[axis y]
mode = active
travel = -0.030 0.030
max_velocity = 0.05
max_acceleration = 0.5
controller = internal_model
feedback_linearization = on
imr_omega0_rad_per_s = 4.71238898038469
antiwindup_gain = 7e-5
derivative_filter_Hz = 50
lqr_weight_h = 459.119941 38.73045726 21246.3488 2231.369139 2701.787843

# phi: the paper regulates it to 0 and prints no poles: theta's (ours).
# Travel: the guides' range about X [P].
[axis theta_x]
mode = active
travel = -0.003 0.003
max_velocity = 0.01
max_acceleration = 0.5
controller = internal_model
feedback_linearization = on
imr_omega0_rad_per_s = 4.71238898038469
antiwindup_gain = 0
derivative_filter_Hz = 50
lqr_weight_h = 2000.452542 200.00225 63299.00524 -1112.81106 9911.916949

[axis theta_y]
mode = active
travel = -0.010 0.010
max_velocity = 0.05
max_acceleration = 0.5
controller = internal_model
feedback_linearization = on
imr_omega0_rad_per_s = 4.71238898038469
antiwindup_gain = 0
derivative_filter_Hz = 50
lqr_weight_h = 2000.452542 200.00225 63299.00524 -1112.81106 9911.916949

# Motors 1..4 [P] Fig. 1: 1, 3 drive the paper's Z (y here), 2, 4 drive X.
[actuator 1]
x_m = 0
y_m = -0.397
thrust_direction_rad = 1.5707963267948966
[actuator 2]
x_m = 0.397
y_m = 0
thrust_direction_rad = 0
[actuator 3]
x_m = 0
y_m = 0.397
thrust_direction_rad = 1.5707963267948966
[actuator 4]
x_m = -0.397
y_m = 0
thrust_direction_rad = 0

# The encoders [P]: 10 um on the translations, 20 urad on the rotations,
# each reading its axis directly (the paper gives the outputs' resolutions,
# not the four vertical encoders' positions).
[sensor 1]
kind = linear_encoder
axis = z
resolution = 10e-6
[sensor 2]
kind = linear_encoder
axis = x
resolution = 10e-6
[sensor 3]
kind = linear_encoder
axis = y
resolution = 10e-6
[sensor 4]
kind = linear_encoder
axis = theta_x
resolution = 20e-6
[sensor 5]
kind = linear_encoder
axis = theta_y
resolution = 20e-6
