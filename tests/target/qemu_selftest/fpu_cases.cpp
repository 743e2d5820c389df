// FPU checks: the M7's FPv5-D16 must reproduce, bit for bit, IEEE-754 results
// computed on the host in exact arithmetic (gen_expected.py). Operands are
// read through volatile so the compiler cannot fold anything at build time:
// every result below comes from a VFP instruction executed on the target
// (the qemu-selftest-uses-hardware-fpu ctest checks those instructions exist).
#include <bit>
#include <cstdint>

#include "maglev/target_test/target_test.hpp"
#include "selftest_expected.hpp"

namespace {

using namespace maglev::selftest;

float load_f32(const volatile std::uint32_t& bits) { return std::bit_cast<float>(static_cast<std::uint32_t>(bits)); }
double load_f64(const volatile std::uint64_t& bits) { return std::bit_cast<double>(static_cast<std::uint64_t>(bits)); }
std::uint32_t bits_of(float value) { return std::bit_cast<std::uint32_t>(value); }
std::uint64_t bits_of(double value) { return std::bit_cast<std::uint64_t>(value); }

float abs_f32(float value) { return value < 0.0F ? -value : value; }
double abs_f64(double value) { return value < 0.0 ? -value : value; }

}  // namespace

MAGLEV_TARGET_TEST(fpu, float32_add_sub_mul_div_match_host_ieee) {
  for (const auto& c : kF32Cases) {
    const volatile std::uint32_t a_bits = c.a;
    const volatile std::uint32_t b_bits = c.b;
    const float a = load_f32(a_bits);
    const float b = load_f32(b_bits);
    TT_CHECK_EQUAL(c.add, bits_of(a + b));
    TT_CHECK_EQUAL(c.sub, bits_of(a - b));
    TT_CHECK_EQUAL(c.mul, bits_of(a * b));
    TT_CHECK_EQUAL(c.div, bits_of(a / b));
  }
}

MAGLEV_TARGET_TEST(fpu, float32_sqrt_matches_host_ieee) {
  for (const auto& c : kF32Cases) {
    const volatile std::uint32_t a_bits = c.a;
    TT_CHECK_EQUAL(c.sqrt_abs_a, bits_of(__builtin_sqrtf(abs_f32(load_f32(a_bits)))));
  }
}

// -ffp-contract=off (top-level CMakeLists.txt) keeps a*b + a as two rounded
// operations, matching the host; an explicit fmaf is one rounding. The table
// has rows where the two differ, so this also proves contraction is off.
MAGLEV_TARGET_TEST(fpu, fused_and_unfused_multiply_add_are_distinct_and_exact) {
  TT_CHECK(kFusedDiffersCount > 0);
  for (const auto& c : kF32Cases) {
    const volatile std::uint32_t a_bits = c.a;
    const volatile std::uint32_t b_bits = c.b;
    const float a = load_f32(a_bits);
    const float b = load_f32(b_bits);
    TT_CHECK_EQUAL(c.fma_ab_a, bits_of(__builtin_fmaf(a, b, a)));
    TT_CHECK_EQUAL(c.mul_then_add_a, bits_of(a * b + a));
  }
}

MAGLEV_TARGET_TEST(fpu, float64_add_mul_div_sqrt_match_host_ieee) {
  for (const auto& c : kF64Cases) {
    const volatile std::uint64_t a_bits = c.a;
    const volatile std::uint64_t b_bits = c.b;
    const double a = load_f64(a_bits);
    const double b = load_f64(b_bits);
    TT_CHECK_EQUAL(c.add, bits_of(a + b));
    TT_CHECK_EQUAL(c.mul, bits_of(a * b));
    TT_CHECK_EQUAL(c.div, bits_of(a / b));
    TT_CHECK_EQUAL(c.sqrt_abs_a, bits_of(__builtin_sqrt(abs_f64(a))));
  }
}

MAGLEV_TARGET_TEST(fpu, int32_float32_conversions_round_and_truncate) {
  for (const auto& c : kCvtCases) {
    const volatile std::uint32_t int_bits = c.int_bits;
    const auto value = static_cast<std::int32_t>(static_cast<std::uint32_t>(int_bits));
    const auto as_float = static_cast<float>(value);
    TT_CHECK_EQUAL(c.float_bits, bits_of(as_float));
    if (c.check_truncation != 0U) {
      TT_CHECK_EQUAL(c.truncated_back, static_cast<std::uint32_t>(static_cast<std::int32_t>(as_float)));
    }
  }
}

MAGLEV_TARGET_TEST(integer, int64_multiply_divide_shift_match_host) {
  for (const auto& c : kI64Cases) {
    const volatile std::uint64_t a_bits = c.a;
    const volatile std::uint64_t b_bits = c.b;
    const auto a = static_cast<std::int64_t>(static_cast<std::uint64_t>(a_bits));
    const auto b = static_cast<std::int64_t>(static_cast<std::uint64_t>(b_bits));
    // Wrapping product via unsigned arithmetic (signed overflow is UB).
    TT_CHECK_EQUAL(c.product, static_cast<std::uint64_t>(a) * static_cast<std::uint64_t>(b));
    TT_CHECK_EQUAL(c.quotient, static_cast<std::uint64_t>(a / b));
    TT_CHECK_EQUAL(c.remainder, static_cast<std::uint64_t>(a % b));
    TT_CHECK_EQUAL(c.a_shr17, static_cast<std::uint64_t>(a >> 17));
  }
}
