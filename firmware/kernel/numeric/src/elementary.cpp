#include "maglev/io/code_placement.hpp"
#include "maglev/numeric/elementary.hpp"

#include <cmath>  // std::ldexp, std::frexp (exact), std::isnan / isinf (classification)
#include <cstdint>
#include <limits>

namespace maglev::numeric {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kHalfPi = 1.57079632679489661923;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// pi/2 as a sum of three doubles whose leading parts have trailing zero
// bits, so k * part is exact for |k| < 2^20 (Cody-Waite): the reduced
// argument keeps ~100 bits of pi/2.
constexpr double kHalfPi1 = 1.5707963267341256141662597656250;       // 33 bits of pi/2
constexpr double kHalfPi2 = 6.0771005063039659765e-11;                 // next bits
constexpr double kHalfPi3 = 2.0222662487111665e-21;                    // the rest
constexpr double kTwoOverPi = 0.63661977236758134308;

// Taylor polynomials on |r| <= pi/4 (+ the reduction's rounding): the first
// omitted term is below 2^-60 relative.
double sin_poly(double r) {
  const double r2 = r * r;
  double s = 1.0 / 355687428096000.0;  // 1/17!
  s = s * -r2 + 1.0 / 1307674368000.0;  // 1/15!
  s = s * -r2 + 1.0 / 6227020800.0;     // 1/13!
  s = s * -r2 + 1.0 / 39916800.0;       // 1/11!
  s = s * -r2 + 1.0 / 362880.0;         // 1/9!
  s = s * -r2 + 1.0 / 5040.0;           // 1/7!
  s = s * -r2 + 1.0 / 120.0;            // 1/5!
  s = s * -r2 + 1.0 / 6.0;              // 1/3!
  return r - r * r2 * s;
}

double cos_poly(double r) {
  const double r2 = r * r;
  double c = 1.0 / 6402373705728000.0;  // 1/18!
  c = c * -r2 + 1.0 / 20922789888000.0;  // 1/16!
  c = c * -r2 + 1.0 / 87178291200.0;     // 1/14!
  c = c * -r2 + 1.0 / 479001600.0;       // 1/12!
  c = c * -r2 + 1.0 / 3628800.0;         // 1/10!
  c = c * -r2 + 1.0 / 40320.0;           // 1/8!
  c = c * -r2 + 1.0 / 720.0;             // 1/6!
  c = c * -r2 + 1.0 / 24.0;              // 1/4!
  // 1 - r^2/2 + r^4 c, the small terms first.
  const double hr2 = 0.5 * r2;
  return (1.0 - hr2) + r2 * r2 * c;
}

// x = k pi/2 + r, |r| <= ~pi/4; returns r and the quadrant k mod 4.
double reduce(double x, int* quadrant) {
  const double k = std::nearbyint(x * kTwoOverPi);
  // k mod 4 through int32 while k fits (one VCVT on the M7; the int64
  // conversion is a libgcc call of ~55 instructions): the same bits.
  *quadrant = (k < 2147483648.0 && k > -2147483648.0) ? static_cast<int>(static_cast<std::int32_t>(k) & 3)
                                                      : static_cast<int>(static_cast<long long>(k) & 3);
  return ((x - k * kHalfPi1) - k * kHalfPi2) - k * kHalfPi3;
}

// 1 / (2n + 1), n = 0..21: the atan and atanh series' coefficients, made at
// compile time (the same correctly rounded quotients the loops computed at
// run time, without 20 divisions per call).
struct OddReciprocals {
  double v[22];
};
constexpr OddReciprocals MakeOddReciprocals() {
  OddReciprocals r{};
  for (int n = 0; n < 22; ++n) r.v[n] = 1.0 / (2.0 * n + 1.0);
  return r;
}
constexpr OddReciprocals kOdd = MakeOddReciprocals();

// 1 / n!, n = 0..20 (n! exact in double up to 22!).
struct InverseFactorials {
  double v[21];
};
constexpr InverseFactorials MakeInverseFactorials() {
  InverseFactorials r{};
  double f = 1.0;
  for (int n = 0; n <= 20; ++n) {
    if (n > 0) f *= n;
    r.v[n] = 1.0 / f;
  }
  return r;
}
constexpr InverseFactorials kInvFact = MakeInverseFactorials();

// atan on [0, tan(pi/12)] by its series (|t| <= 0.268: 20 terms leave < 1e-23).
double atan_series(double t) {
  const double t2 = t * t;
  double s = kOdd.v[20];
  for (int n = 19; n >= 0; --n) s = s * -t2 + kOdd.v[n];
  return t * s;
}

constexpr double kTanPiOver12 = 0.26794919243112270647;  // 2 - sqrt(3)
constexpr double kSqrt3 = 1.73205080756887729353;
constexpr double kPiOver6 = 0.52359877559829887308;

// ln 2 split so that k * kLn2Hi is exact for |k| < 2^11.
constexpr double kLn2Hi = 0.693145751953125;           // 0x3FE62E40 00000000
constexpr double kLn2Lo = 1.42860682030941723212e-6;   // ln 2 - kLn2Hi
constexpr double kLn2 = 0.69314718055994530942;

}  // namespace

double dsin(double x) {
  if (std::isnan(x) || std::isinf(x)) return kNaN;
  int q = 0;
  const double r = reduce(x, &q);
  switch (q) {
    case 0: return sin_poly(r);
    case 1: return cos_poly(r);
    case 2: return -sin_poly(r);
    default: return -cos_poly(r);
  }
}

double dcos(double x) {
  if (std::isnan(x) || std::isinf(x)) return kNaN;
  int q = 0;
  const double r = reduce(x, &q);
  switch (q) {
    case 0: return cos_poly(r);
    case 1: return -sin_poly(r);
    case 2: return -cos_poly(r);
    default: return sin_poly(r);
  }
}

// Both from one reduction: exactly dsin(x) and dcos(x) (the same r, the same
// polynomials, the same quadrant selection), for the references' ticks.
void dsincos(double x, double* sin_out, double* cos_out) {
  if (std::isnan(x) || std::isinf(x)) {
    *sin_out = kNaN;
    *cos_out = kNaN;
    return;
  }
  int q = 0;
  const double r = reduce(x, &q);
  const double sp = sin_poly(r), cp = cos_poly(r);
  switch (q) {
    case 0: *sin_out = sp; *cos_out = cp; break;
    case 1: *sin_out = cp; *cos_out = -sp; break;
    case 2: *sin_out = -sp; *cos_out = -cp; break;
    default: *sin_out = -cp; *cos_out = sp; break;
  }
}

MAGLEV_CONFIG_CODE double dtan(double x) {
  if (std::isnan(x) || std::isinf(x)) return kNaN;
  int q = 0;
  const double r = reduce(x, &q);
  const double s = sin_poly(r), c = cos_poly(r);
  return (q & 1) ? -c / s : s / c;
}

double datan(double x) {
  if (std::isnan(x)) return kNaN;
  const bool negative = x < 0.0;
  double t = negative ? -x : x;
  double offset = 0.0;
  bool complement = false;
  if (t > 1.0) {  // atan t = pi/2 - atan(1/t)
    t = 1.0 / t;
    complement = true;
  }
  if (t > kTanPiOver12) {  // atan t = pi/6 + atan((t sqrt3 - 1) / (t + sqrt3))
    t = (t * kSqrt3 - 1.0) / (t + kSqrt3);
    offset = kPiOver6;
  }
  double a = offset + atan_series(t);
  if (complement) a = kHalfPi - a;
  return negative ? -a : a;
}

double datan2(double y, double x) {
  if (std::isnan(x) || std::isnan(y)) return kNaN;
  if (x == 0.0 && y == 0.0) return std::signbit(x) ? (std::signbit(y) ? -kPi : kPi) : y;
  if (std::isinf(x) || std::isinf(y)) {
    // Directions only: scale both to finite values that keep the quadrant.
    const double xs = std::isinf(x) ? (x > 0 ? 1.0 : -1.0) : std::copysign(1e-300, x);
    const double ys = std::isinf(y) ? (y > 0 ? 1.0 : -1.0) : std::copysign(0.0, y);
    return datan2(ys, xs);
  }
  const double ax = x < 0.0 ? -x : x, ay = y < 0.0 ? -y : y;
  // The angle of (|x|, |y|) in [0, pi/2] from the smaller ratio.
  double a = ay <= ax ? datan(ay / ax) : kHalfPi - datan(ax / ay);
  if (x < 0.0) a = kPi - a;
  return y < 0.0 || (y == 0.0 && std::signbit(y)) ? -a : a;
}

MAGLEV_CONFIG_CODE double dexp(double x) {
  if (std::isnan(x)) return kNaN;
  if (x > 709.78) return kInf;
  if (x < -745.2) return 0.0;
  const double k = std::nearbyint(x / kLn2);
  const double r = (x - k * kLn2Hi) - k * kLn2Lo;  // |r| <= ~0.347
  double s = kInvFact.v[20];
  for (int n = 19; n >= 1; --n) s = s * r + kInvFact.v[n];
  const double e = 1.0 + r * s;
  return std::ldexp(e, static_cast<int>(k));
}

MAGLEV_CONFIG_CODE double dlog(double x) {
  if (std::isnan(x) || x < 0.0) return kNaN;
  if (x == 0.0) return -kInf;
  if (std::isinf(x)) return kInf;
  int e = 0;
  double m = std::frexp(x, &e);  // x = m 2^e, m in [0.5, 1)
  if (m < 0.70710678118654752440) {
    m *= 2.0;
    e -= 1;
  }
  // ln m = 2 atanh(s), s = (m - 1) / (m + 1), |s| <= 0.1716: 21 terms leave < 1e-32.
  const double s = (m - 1.0) / (m + 1.0);
  const double s2 = s * s;
  double t = kOdd.v[21];
  for (int n = 20; n >= 0; --n) t = t * s2 + kOdd.v[n];
  const double ln_m = 2.0 * s * t;
  return (e * kLn2Hi + ln_m) + e * kLn2Lo;
}

MAGLEV_CONFIG_CODE double dpow(double a, double b) {
  if (std::isnan(a) || std::isnan(b) || a < 0.0) return kNaN;
  if (b == 0.0) return 1.0;
  if (a == 0.0) return b > 0.0 ? 0.0 : kNaN;
  if (a == 1.0) return 1.0;
  return dexp(b * dlog(a));
}

}  // namespace maglev::numeric
