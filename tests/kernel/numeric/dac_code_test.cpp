// maglev/numeric/dac_code.hpp: DacCode rounds half away from zero and
// saturates to [-32768, 32767] with NaN -> 0; SymmetricDacCode the same into
// [-32767, 32767]. Every half code of the range and both neighbours, the
// bounds, values past the int32 range, signed zeros, infinities and NaN, on
// the host and on the M7 (its VRINTA / VCVT / SSAT form).
#include <cmath>
#include <cstdint>
#include <limits>

#include "maglev/numeric/dac_code.hpp"

#include <CppUTest/TestHarness.h>

namespace {

using maglev::numeric::DacCode;
using maglev::numeric::SymmetricDacCode;

int Reference(double v, double low) {
  if (!(v == v)) return 0;
  const double c = v > 32767.0 ? 32767.0 : (v < low ? low : v);
  return static_cast<int>(std::round(c));
}

// v, its two neighbours, both signs.
template <typename F>
void AroundEachSign(double v, F check) {
  for (double s : {1.0, -1.0}) {
    const double x = s * v;
    check(x);
    check(std::nextafter(x, INFINITY));
    check(std::nextafter(x, -INFINITY));
  }
}

}  // namespace

TEST_GROUP(DacCode){};

TEST(DacCode, RoundsHalfAwayAndSaturates) {
  int checked = 0;
  auto check = [&](double v) {
    CHECK_EQUAL(Reference(v, -32768.0), static_cast<int>(DacCode(v)));
    CHECK_EQUAL(Reference(v, -32767.0), static_cast<int>(SymmetricDacCode(v)));
    ++checked;
  };
  for (int k = 0; k <= 33000; ++k) {
    for (double d : {0.0, 0.25, 0.5}) AroundEachSign(k + d, check);
  }
  for (double v : {2147483647.0, 2147483648.0, 4294967296.0, 1e15, 1e300}) AroundEachSign(v, check);
  const double special[] = {0.0, -0.0, INFINITY, -INFINITY, std::numeric_limits<double>::quiet_NaN()};
  for (double v : special) check(v);
  CHECK(checked > 590000);
}

TEST(DacCode, SymmetricRangeEndsAtMinus32767) {
  CHECK_EQUAL(-32768, static_cast<int>(DacCode(-32768.0)));
  CHECK_EQUAL(-32767, static_cast<int>(SymmetricDacCode(-32768.0)));
  CHECK_EQUAL(-32767, static_cast<int>(SymmetricDacCode(-1e30)));
  CHECK_EQUAL(-32767, static_cast<int>(SymmetricDacCode(-INFINITY)));
  CHECK_EQUAL(32767, static_cast<int>(SymmetricDacCode(INFINITY)));
  CHECK_EQUAL(0, static_cast<int>(SymmetricDacCode(std::numeric_limits<double>::quiet_NaN())));
  CHECK_EQUAL(0, static_cast<int>(SymmetricDacCode(-std::numeric_limits<double>::quiet_NaN())));
}

// The largest float below one half is a code of 0. (The PMLSM kernel's own
// float form, code + 0.5f then truncation, gave 1 there: the sum rounds to 1.)
TEST(DacCode, JustBelowAHalfRoundsDown) {
  const float below_half = std::nextafter(0.5f, 0.0f);
  CHECK_EQUAL(1, static_cast<int>(below_half + 0.5f));  // what the float form did
  CHECK_EQUAL(0, static_cast<int>(SymmetricDacCode(static_cast<double>(below_half))));
  CHECK_EQUAL(0, static_cast<int>(SymmetricDacCode(static_cast<double>(-below_half))));
}
