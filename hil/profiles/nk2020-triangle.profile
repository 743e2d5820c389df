# Paper 003: Nguyen & Kim (Precision Engineering 2020), triangular layout,
# eq (8), Fig. 8: three forcers in a Y at 120 deg (alpha = pi/6), coils 7
# and 8 unused. Same platen, coils, sensors and gains as nk2017-cross.
[stage]
name = nk2020-triangle
title = Paper 003: three forcers in a Y (triangular layout, eq (8), alpha = 30 deg)
paper = 3
family = halbach_lorentz
servo_rate_Hz = 2500
# Sec. V: close x, y, theta_z; feed-forward lift; close z; close the tilts.
startup = close_in_plane lift_feedforward close_vertical close_tilts ready

[body]
mass_kg = 0.75
inertia_x_kgm2 = 0.0019
inertia_y_kgm2 = 0.0019
inertia_z_kgm2 = 0.0036
gravity_m_per_s2 = 9.80665

[halbach]
layout = triangle
triangle_alpha_rad = 0.5235987755982988
lever_arm_m = 0.05207
pitch_m = 0.0508
magnet_thickness_m = 0.0127
# eq (29): identified 2 b*(z0)
two_b_star_N_per_A = 1.7037
coil_effective_length_m = 0.04229
coil_side_width_m = 0.00965
coil_thickness_m = 0.00254
coil_turns = 30
rest_gap_m = 0.0016

[limits]
peak_current_A = 4
rms_current_A = 3
# AD5764 +-10 V x PA12A 0.5 A/V
hardware_current_A = 5
# (ours) the controlled landing touches down at 0.085 mm/s on the bench
landing_speed_m_per_s = 0.0002
nominal_height_m = 30e-6

# Axis loops: paper 000 eqs (27), (28), (32), (33) as 2-DOF PIDs; travel
# 56 mm x 35 mm (Sec. V).
[axis x]
mode = active
travel = -0.028 0.028
max_velocity = 0.15
max_acceleration = 1.5
controller = pid2dof
kp = 36000
ki = 2400000
kd = 100
setpoint_weight_p = 0.4
effort_limit_A = 4

[axis y]
mode = active
travel = -0.0175 0.0175
max_velocity = 0.15
max_acceleration = 1.5
controller = pid2dof
kp = 36000
ki = 2400000
kd = 100
setpoint_weight_p = 0.4
effort_limit_A = 4

[axis theta_z]
mode = active
travel = -4e-3 4e-3
max_velocity = 0.05
max_acceleration = 0.5
controller = pid2dof
kp = 300
ki = 24000
kd = 1
setpoint_weight_p = 0.5
effort_limit_A = 4

[axis z]
mode = active
# eq (29): k = 94600 N/m, c = 890 N s/m over m = 0.75 kg
open_loop_stiffness_per_s2 = 126133.33333333333
open_loop_damping_per_s = 1186.6666666666667
travel = 10e-6 38e-6
max_velocity = 200e-6
max_acceleration = 5e-3
controller = pid2dof
kp = 40000
ki = 560000
kd = 0
setpoint_weight_p = 1
effort_limit_A = 8

[axis theta_x]
mode = active
# eqs (30)-(31): 128 N m/rad, 1.21 N m s/rad over I = 0.0019 kg m^2
open_loop_stiffness_per_s2 = 67368.42105263157
open_loop_damping_per_s = 636.8421052631579
travel = -200e-6 200e-6
max_velocity = 1e-3
max_acceleration = 0.05
controller = pid2dof
kp = 70
ki = 17600
kd = 0.09
setpoint_weight_p = 0.5
effort_limit_A = 4

[axis theta_y]
mode = active
# eqs (30)-(31): 128 N m/rad, 1.21 N m s/rad over I = 0.0019 kg m^2
open_loop_stiffness_per_s2 = 67368.42105263157
open_loop_damping_per_s = 636.8421052631579
travel = -200e-6 200e-6
max_velocity = 1e-3
max_acceleration = 0.05
controller = pid2dof
kp = 70
ki = 17600
kd = 0.09
setpoint_weight_p = 0.5
effort_limit_A = 4

# Sensor noise: rms per sample, the parts' datasheet figures (docs/PLANT.md
# section 11: HP 5517D-class interferometer 0.3 nm, Keyence LK-G10-class laser
# displacement sensor 10 nm); the bench's nominal and as-built plants use them.
# Sensors: three interferometer axes (x; y1, y2 100 mm apart), three laser
# displacement sensors (ours: 123 mm square), two two-axis Hall sensors.
[sensor 1]
kind = interferometer
x_m = 0
y_m = 0
direction_rad = 0
resolution = 0.618e-9
noise = 0.3e-9

[sensor 2]
kind = interferometer
x_m = -0.05
y_m = 0
direction_rad = 1.5707963267948966
resolution = 0.618e-9
noise = 0.3e-9

[sensor 3]
kind = interferometer
x_m = 0.05
y_m = 0
direction_rad = 1.5707963267948966
resolution = 0.618e-9
noise = 0.3e-9

[sensor 4]
kind = laser_displacement
x_m = 0.0615
y_m = 0.0615
resolution = 20e-6
noise = 10e-9

[sensor 5]
kind = laser_displacement
x_m = -0.0615
y_m = 0.0615
resolution = 20e-6
noise = 10e-9

[sensor 6]
kind = laser_displacement
x_m = -0.0615
y_m = -0.0615
resolution = 20e-6
noise = 10e-9

[sensor 7]
kind = hall
x_m = -0.030
y_m = -0.030

[sensor 8]
kind = hall
x_m = -0.0173
y_m = -0.0173
