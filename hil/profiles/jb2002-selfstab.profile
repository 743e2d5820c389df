# Paper 001: Jung & Baek, "Development of a novel maglev positioner with
# self-stabilizing property" (Mechatronics 2002). A 0.173 kg rotor with nine
# permanent magnets over nine air-core solenoids, passively stable in all six
# axes at the nominal currents; only x and z closed-loop (Fig. 8). Values
# from the paper unless marked (ours), (fitted) or [D] (derived from printed
# numbers); docs/PAPER-001.md explains each, docs/STAGES.md every key.
[stage]
name = jb2002-selfstab
title = Paper 001: self-stabilizing solenoid-magnet positioner, x and z closed-loop
paper = 1
family = solenoid_magnet
# (ours) the paper gives no servo rate
servo_rate_Hz = 1000
# Docked at rest; the nominal currents lift it (Section 4's docking mechanism).
startup = lift_off_from_dock ready

[body]
# Table 1
mass_kg = 0.173
inertia_x_kgm2 = 4.26e-4
inertia_y_kgm2 = 4.29e-4
inertia_z_kgm2 = 8.18e-4
# (ours)
gravity_m_per_s2 = 9.81

[solenoid]
# Table 1: magnetization, PM volume (r 5 mm x 10 mm), solenoid volume, L
magnetization_A_per_m = 867000
magnet_volume_m3 = 0.7854e-6
solenoid_volume_m3 = 20.42e-6
length_m = 0.05
# (fitted) r1 is not printed: fitted to the alpha damping row of (13)
radius_r1_m = 0.05126
# Table 2
radius_r2_m = 0.0715
nominal_current_in_plane_A = 0.4273
nominal_current_out_of_plane_A = 0.535
turns_in_plane = 996
turns_out_of_plane = 986
# (fitted) not printed for the optimized coils: fitted to the z damping row of (13)
coil_resistance_Ohm = 6.7223
# [D] from (13): k_ipi = 2 m 3.4239, k_opi = m 6.1124 (per coil, at the nominal position)
force_constant_in_plane_N_per_A = 1.1846694
force_constant_out_of_plane_N_per_A = 1.0574452

[limits]
# (ours) coil amplifiers +-2 A (the DAC's full scale); nominal + efforts stay below 1.5 A
peak_current_A = 1.5
rms_current_A = 1.0
hardware_current_A = 2.0
# (ours)
landing_speed_m_per_s = 0.05
# (ours) docking stop 2.5 mm below the nominal position
nominal_height_m = 2.5e-3

# Closed loop: x and z (Fig. 8), PID with the 10 Hz Butterworth of Section 4
# in the feedback path. Gains (ours): designed on (13) with the filter, the
# 1 ms tick and a 1.5-tick delay in the loop for >= 40 deg phase margin
# (z: 5.1 Hz crossover, 40 deg; x: 4.2 Hz, 50 deg); the paper prints none.
[axis x]
mode = active
open_loop_stiffness_per_s2 = 150
open_loop_damping_per_s = 3.6369
travel = -2e-3 2e-3
max_velocity = 1e-3
max_acceleration = 1
controller = pid2dof
kp = 2
ki = 60
kd = 0.6
derivative_filter_Hz = 100
effort_limit_A = 0.2
filter1 = butterworth2 10

[axis z]
mode = active
open_loop_stiffness_per_s2 = 556.6771
open_loop_damping_per_s = 2.8648
# The PSDs read +-2.35 mm; the schedule covers +-2 mm (a reference between
# the two is refused as outside the schedule).
travel = -2.2e-3 2.2e-3
max_velocity = 1e-3
max_acceleration = 1
controller = pid2dof
kp = 5
ki = 200
kd = 1.0
derivative_filter_Hz = 100
effort_limit_A = 0.5
filter1 = butterworth2 10
# Gain schedule over z (Section 4: the nonlinear model linearized at a grid
# of operating points): at each height the kp and kd scales that give the z
# loop around the bench plant linearized there the same response at the
# nominal 5.07 Hz crossover as at z = 0 (gain and phase). Printed by
# `maglev-hil selfstab-schedule --profile jb2002-selfstab`; the suite's
# schedule_margins checks the table against it.
schedule = -2e-3 1.1430 1.2573; -1e-3 1.0753 1.1102; 0 1 1; 1e-3 0.9214 0.9236; 2e-3 0.8431 0.8785

# Passive (the paper's uncontrolled axes): the nominal currents only. Open
# loop stiffness and damping per unit inertia from (13).
[axis y]
mode = passive
open_loop_stiffness_per_s2 = 150
open_loop_damping_per_s = 3.6369
travel = -2e-3 2e-3

[axis theta_x]
mode = passive
open_loop_stiffness_per_s2 = 150
open_loop_damping_per_s = 1.5286
travel = -20e-3 20e-3

[axis theta_y]
mode = passive
open_loop_stiffness_per_s2 = 150
open_loop_damping_per_s = 1.5286
travel = -20e-3 20e-3

[axis theta_z]
mode = passive
open_loop_stiffness_per_s2 = 650.4952
open_loop_damping_per_s = 7.5796
travel = -20e-3 20e-3

# Three two-axis PSDs at 120 deg on the stator's inner ring (Section 4);
# each reads the (tangential, vertical) spot of a radial LED beam. Ring
# radius 0.1 m and first angle 0 deg (ours). 12-bit A/D over 4.7 mm:
# 1.1474609375 um per count [P]. The bench models the quantization, not
# the electronics noise.
[sensor 1]
kind = psd
x_m = 0.1
y_m = 0
resolution = 1.1474609375e-6
noise = 0

[sensor 2]
kind = psd
x_m = -0.05
y_m = 0.08660254037844387
resolution = 1.1474609375e-6
noise = 0

[sensor 3]
kind = psd
x_m = -0.05
y_m = -0.08660254037844387
resolution = 1.1474609375e-6
noise = 0
