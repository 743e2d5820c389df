// The kernel's own elementary functions in double: sin, cos, tan, atan2,
// exp, log, pow. Deterministic by construction: only +, -, *, / and exact
// scaling by powers of two (std::ldexp / std::frexp), in a fixed order, with
// -ffp-contract=off everywhere. So the host and the Cortex-M7 compute the
// same bits, which glibc's and newlib's libm do not guarantee (measured: 1 ulp
// apart on 3-18 % of arguments, docs/PERFORMANCE.md). Every kernel, profile
// and lab-tools computation uses these instead of <cmath>'s.
//
// Accuracy (tested against <cmath> over dense sweeps, tests/kernel/numeric):
//   sin, cos  |x| <= 1e6:    abs. error <= 4e-16 + |x| 2e-22  (Cody-Waite reduction by pi/2)
//   tan       |x| < pi/2 - 1e-6: rel. error <= 1e-15
//   atan2     everywhere:    abs. error <= 5e-16 rad
//   exp       |x| <= 700:    rel. error <= 1e-15
//   log       x > 0:         abs. error <= 4e-16 + 3e-16 |log x|
//   pow       a > 0:         rel. error <= 1e-15 (1 + |b log a|)
// They are not correctly rounded: the point is that they agree everywhere.
// Not for the hot path: a few hundred FPU operations each.
#pragma once

namespace maglev::numeric {

double dsin(double x);
double dcos(double x);
// *sin_out = dsin(x), *cos_out = dcos(x), bit for bit, from one reduction.
void dsincos(double x, double* sin_out, double* cos_out);
double dtan(double x);
double datan2(double y, double x);
double datan(double x);
double dexp(double x);
double dlog(double x);  // x <= 0: NaN (x < 0) or -infinity (x == 0)
double dpow(double a, double b);  // a > 0, or a == 0 with b > 0; otherwise NaN

}  // namespace maglev::numeric
