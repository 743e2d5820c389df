// The seed stage's nominal physical parameters: one source of truth for the
// kernel's default configuration AND the HIL plant's default model, so the two
// can never silently disagree. Values are from paper 000 (Nguyen & Kim 2017)
// unless marked "(ours)": those are sensor/electronics choices the paper does
// not state; docs/ARCHITECTURE.md explains each choice.
//
// Frames: world XYZ fixed to the magnet matrix (Z up, origin at a phase zero of
// the Halbach fundamental so that B_x ~ sin(gamma_1 x) at sensor height),
// platen X'Y'Z' at the platen centre. z is the height above the landed rest
// position (air gap = kRestGap_m + z).
#pragma once

namespace maglev::io::stage {

inline constexpr double kPi = 3.14159265358979323846;

// --- Halbach magnet array, eqs (1)-(3) -------------------------------------
inline constexpr double kPitch_m = 0.0508;             // L, spatial pitch
inline constexpr double kGamma1_per_m = 2.0 * kPi / kPitch_m;
inline constexpr double kMagnetThickness_m = 0.0127;  // Delta
inline constexpr double kMu0 = 4.0e-7 * kPi;

// --- Coils, Sections II-III ------------------------------------------------
inline constexpr double kCoilEffectiveLength_m = 0.04229;  // p
inline constexpr double kCoilSideWidth_m = 0.00965;        // a
inline constexpr double kCoilThickness_m = 0.00254;        // d
inline constexpr int kCoilTurns = 30;                      // N
inline constexpr double kCoilResistance_Ohm = 0.19;
inline constexpr double kCoilInductance_H = 59e-6;
inline constexpr double kRestGap_m = 0.0016;  // magnets' top to coils' bottom, landed (z0)
// Identified 2 b*(z0), eq (29): force per ampere of control effort.
inline constexpr double kTwoBStarIdentified_N_per_A = 1.7037;

// --- Platen, Section III ---------------------------------------------------
inline constexpr double kMass_kg = 0.75;
inline constexpr double kIx_kgm2 = 0.0019;
inline constexpr double kIy_kgm2 = 0.0019;
inline constexpr double kIz_kgm2 = 0.0036;
inline constexpr double kLeverArm_m = 0.05207;  // l in A, eq (18)
inline constexpr double kGravity_m_per_s2 = 9.80665;
inline constexpr double kTestPayload_kg = 0.5396;  // Fig. 9

// --- Identified out-of-plane suspension, eqs (29)-(31) ---------------------
inline constexpr double kZStiffness_N_per_m = 94600.0;
inline constexpr double kZDamping_Ns_per_m = 890.0;
inline constexpr double kTiltStiffness_Nm_per_rad = 128.0;
inline constexpr double kTiltDamping_Nms_per_rad = 1.21;
// Height above rest of the nominal levitation point ("within 40 um", Sec. V).
// (ours) 30 um: inside the 40 um envelope with 10 um margin for steps.
inline constexpr double kNominalHeight_m = 30e-6;
inline constexpr double kZEnvelope_m = 40e-6;

// --- Commutation base points, eq (19)/(23) ---------------------------------
// Every coil j obeys F_(tangential,z) = b* i_j (sin psi_j, cos psi_j) with
// psi_j = gamma_1 * (base-point position along its axis) + kCoilPhase_rad[j].
// These offsets are exactly what makes eq (19) hold; the plant's geometry is
// derived from them, the kernel's S_xy (eq 23) assumes them.
inline constexpr double kCoilPhase_rad[8] = {0.0, -kPi / 2, kPi / 2, 0.0,
                                            kPi / 2, kPi, kPi, -kPi / 2};
// (ours) base-point offsets of x2 and y8 from the platen centre.
inline constexpr double kBasePointX2_m = 0.0;
inline constexpr double kBasePointY8_m = 0.0;
// (ours) Each coil's centre along its array axis (x for the Fx coils 1, 2, 5, 6;
// y for the Fy coils 3, 4, 7, 8), from its forcer's centre, in quarter pitches:
// a coil sits at 0 when its phase allows it, else at +L/4 (pairs 1&2, 3&4) or
// -L/4 (5&6, 7&8), so the layout is symmetric under a 180 deg turn and a
// pair's four sides are L/4 apart (Sec. III; the plant builds its coil sides
// from these phases by that rule, hil/plant BuildArraySides). A forcer's
// vertical force therefore acts between its coils' centres, weighted by the
// commutation (Fig. 5(b)): the force allocation takes it into account.
inline constexpr int kCoilCentreQuarterPitches[8] = {0, 1, 1, 0, -1, 0, 0, -1};

// --- Servo rate -------------------------------------------------------------
// (ours) 2.5 kHz: theta_z crosses over at 81.3 Hz (fs/fc = 31) and the
// sensor + actuator CAN FD frames take <= 48% of a 1/5 Mbit/s bus.
// docs/CAN.md holds the arithmetic.
// The DEFAULT servo rate: the rate a stage boots at with no stored
// configuration (register servo.rate, issue 16). Everything that runs at the
// servo rate reads the configured KernelConfig::servo_rate_Hz, never this.
inline constexpr double kServoRate_Hz = 2500.0;
// The servo rates the controller offers (register servo.rate; the bench's
// --servo-rate): 400, 200, 100 and 50 us, each a whole number of
// microseconds and of 480 MHz CPU / 240 MHz timer cycles.
inline constexpr double kSupportedServoRates_Hz[] = {2500.0, 5000.0, 10000.0, 20000.0};
constexpr bool is_supported_servo_rate(double rate_Hz) {
  for (double r : kSupportedServoRates_Hz) {
    if (rate_Hz == r) return true;
  }
  return false;
}

// --- Interferometers (ours: HP 5517D + 10706B plane-mirror optics) ----------
inline constexpr double kWavelength_m = 632.991e-9;
inline constexpr int kInterferometerFold = 4;            // plane mirror: lambda/4 optical
inline constexpr int kInterferometerInterpolation = 256; // electronic interpolation
inline constexpr double kInterferometerLsb_m =
    kWavelength_m / (kInterferometerFold * kInterferometerInterpolation);  // 0.618 nm
// Default beam layout "x, y1, y2": x beam along X at y = 0; y beams along Y at
// x = -/+ kYBeamSeparation_m/2. theta_z = (y2 - y1) / separation.
inline constexpr double kYBeamSeparation_m = 0.100;

// --- Laser displacement sensors (ours) --------------------------------------
// +-10 V <-> +-200 um about kDisplacementZeroHeight_m above rest; 16-bit ADC,
// 6.1 nm LSB. Positions in the platen frame (frame corners of the 143 mm frame).
inline constexpr double kDisplacementScale_m_per_V = 20e-6;
inline constexpr double kDisplacementZeroHeight_m = 100e-6;
inline constexpr double kDisplacementSensorX_m[3] = {0.0615, -0.0615, -0.0615};
inline constexpr double kDisplacementSensorY_m[3] = {0.0615, 0.0615, -0.0615};

// --- Hall sensors (ours) -----------------------------------------------------
// Two two-axis Hall sensors measuring B_x and B_y. Sensor B sits a quarter
// pitch from sensor A in both X and Y, so A and B read sin and cos of each
// axis' phase: phase_x = atan2(A.Bx, B.Bx), phase_y = atan2(A.By, B.By).
inline constexpr double kHallAX_m = -0.030;
inline constexpr double kHallAY_m = -0.030;
inline constexpr double kHallBX_m = kHallAX_m + kPitch_m / 4;
inline constexpr double kHallBY_m = kHallAY_m + kPitch_m / 4;
inline constexpr double kHallHeightAboveMagnets_m = 0.0016;  // (ours)
inline constexpr double kHallSensitivity_V_per_T = 20.0;     // (ours)

// --- ADC / DAC / amplifiers (ours) ------------------------------------------
inline constexpr double kAdcFullScale_V = 10.0;  // AD7606 +-10 V range, 16 bit
inline constexpr double kDacFullScale_V = 10.0;  // AD5764 +-10 V, 16 bit
inline constexpr double kAmplifierGain_A_per_V = 0.5;         // PA12A transconductance
inline constexpr double kCurrentMonitorGain_V_per_A = 2.0;    // +-5 A over +-10 V
inline constexpr double kPeakCoilCurrent_A = 4.0;             // amplifier/coil limit
inline constexpr double kRmsCoilCurrent_A = 3.0;              // thermal limit

// --- Travel (Sec. V: 56 mm x 35 mm with the mirrors) ------------------------
inline constexpr double kTravelX_m = 0.056;
inline constexpr double kTravelY_m = 0.035;

}  // namespace maglev::io::stage
