#!/usr/bin/env python3
"""Generates expected IEEE-754 results for maglev-qemu-selftest, on the host.

usage: gen_expected.py <out.hpp>

Every float32/float64 result is computed EXACTLY (fractions.Fraction) and
rounded once to nearest-even in software, so the table does not depend on the
host's FPU or compiler. The M7 must reproduce every bit pattern.
sqrt uses math.sqrt (correctly rounded binary64) followed by one rounding to
binary32; that double rounding is exact for sqrt (53 >= 2*24 + 2).
"""
import math
import struct
import sys
import zlib
from fractions import Fraction

F32_MAX_EXP = 127
F32_MANT = 23
F32_MIN_EXP = -126


def f32_bits(x: float) -> int:
    return struct.unpack("<I", struct.pack("<f", x))[0]


def f32_from_bits(b: int) -> float:
    return struct.unpack("<f", struct.pack("<I", b))[0]


def f64_bits(x: float) -> int:
    return struct.unpack("<Q", struct.pack("<d", x))[0]


def round_half_even(q: Fraction) -> int:
    n = q.numerator // q.denominator
    r = q - n
    if r > Fraction(1, 2) or (r == Fraction(1, 2) and n % 2 == 1):
        n += 1
    return n


def round_to_f32_bits(q: Fraction, zero_sign: int = 0) -> int:
    """Round an exact rational to binary32, round-to-nearest-even."""
    if q == 0:
        return 0x80000000 if zero_sign else 0
    sign = 0x80000000 if q < 0 else 0
    a = abs(q)
    e = a.numerator.bit_length() - a.denominator.bit_length()
    if Fraction(2) ** e > a:
        e -= 1
    while Fraction(2) ** (e + 1) <= a:
        e += 1
    quantum = Fraction(2) ** (max(e, F32_MIN_EXP) - F32_MANT)
    n = round_half_even(a / quantum)
    v = n * quantum
    if v >= Fraction(2) ** (F32_MAX_EXP + 1):
        return sign | 0x7F800000
    return sign | f32_bits(float(v))  # v is exactly representable


def round_to_f64(q: Fraction) -> float:
    return q.numerator / q.denominator  # Python int true division: correctly rounded


class Lcg:
    """Deterministic generator so the table is reproducible."""

    def __init__(self, seed: int):
        self.state = seed

    def next(self) -> int:
        self.state = (self.state * 6364136223846793005 + 1442695040888963407) % 2**64
        return self.state >> 32


def main() -> None:
    out = sys.argv[1]
    rng = Lcg(0x6D61676C6576)  # "maglev"

    # float32 operand pairs: hand-picked edge cases + pseudo-random normals.
    pairs = [
        (1.0, 3.0), (0.1, 0.2), (2.0, 1e-8), (16777216.0, 1.0), (16777217.0, 1.0),
        (3.4e38, 3.4e38),          # overflow to +inf on add and mul
        (1.0e-38, 1.0e-3),         # subnormal product (FZ must be off)
        (1.17549435e-38, 3.0),     # smallest normal / 3 -> subnormal
        (-7.5, 0.3), (123456.789, -0.000321), (1e30, 1e-30), (math.pi, math.e),
    ]
    for _ in range(36):
        a = f32_from_bits((rng.next() & 0x807FFFFF) | ((rng.next() % 60 + 97) << 23))
        b = f32_from_bits((rng.next() & 0x807FFFFF) | ((rng.next() % 60 + 97) << 23))
        pairs.append((a, b))

    f32_rows = []
    for a, b in pairs:
        ab, bb = f32_bits(a), f32_bits(b)
        fa, fb = Fraction(f32_from_bits(ab)), Fraction(f32_from_bits(bb))
        add = round_to_f32_bits(fa + fb)
        sub = round_to_f32_bits(fa - fb)
        mul = round_to_f32_bits(fa * fb)
        div = round_to_f32_bits(fa / fb)
        sqrt = round_to_f32_bits(Fraction(math.sqrt(abs(float(fa)))))
        # fused a*b + a: one rounding; mul_add: two roundings (no contraction).
        fma = round_to_f32_bits(fa * fb + fa)
        if (mul & 0x7F800000) == 0x7F800000:
            mul_add = mul  # inf + finite
        else:
            mul_add = round_to_f32_bits(Fraction(f32_from_bits(mul)) + fa)
        f32_rows.append((ab, bb, add, sub, mul, div, sqrt, fma, mul_add))

    fused_differs = sum(1 for r in f32_rows if r[7] != r[8])

    # float64: random normals; no overflow by construction (exponents moderate).
    f64_rows = []
    for _ in range(24):
        hi = (rng.next() & 0x800FFFFF) | ((rng.next() % 200 + 923) << 20)
        a = struct.unpack("<d", struct.pack("<Q", (hi << 32) | rng.next()))[0]
        hi = (rng.next() & 0x800FFFFF) | ((rng.next() % 200 + 923) << 20)
        b = struct.unpack("<d", struct.pack("<Q", (hi << 32) | rng.next()))[0]
        fa, fb = Fraction(a), Fraction(b)
        f64_rows.append((f64_bits(a), f64_bits(b),
                         f64_bits(round_to_f64(fa + fb)), f64_bits(round_to_f64(fa * fb)),
                         f64_bits(round_to_f64(fa / fb)), f64_bits(math.sqrt(abs(a)))))

    # int32 -> float32 conversions (rounding) and float32 -> int32 (truncation).
    # truncated_back = (int32)(float)value when that is in range (C++ leaves
    # out-of-range conversion undefined, so such rows are not checked: flag 0).
    cvt_rows = []
    for value in [16777217, -16777219, 2147483647, -2147483647 - 1, 123456789, 7, -33554435]:
        fbits = round_to_f32_bits(Fraction(value))
        back = int(f32_from_bits(fbits))  # int() truncates toward zero
        in_range = -2**31 <= back < 2**31
        cvt_rows.append((value & 0xFFFFFFFF, fbits, (back if in_range else 0) & 0xFFFFFFFF, int(in_range)))

    # int64 arithmetic through libgcc helpers (__aeabi_ldivmod) and umull.
    i64_rows = []
    for _ in range(16):
        a = ((rng.next() << 32) | rng.next()) - 2**63
        b = (((rng.next() << 32) | rng.next()) >> (rng.next() % 40 + 1)) - 2**20  # int64 range
        if b == 0:
            b = 3
        prod = (a * b) % 2**64
        quot = abs(a) // abs(b) * (1 if (a < 0) == (b < 0) else -1)
        rem = a - quot * b
        i64_rows.append((a % 2**64, b % 2**64, prod, quot % 2**64, rem % 2**64, (a >> 17) % 2**64))

    pattern = [rng.next() for _ in range(64)]
    crc = zlib.crc32(b"".join(struct.pack("<I", w) for w in pattern))

    with open(out, "w", encoding="ascii") as f:
        w = f.write
        w("// GENERATED by tests/target/qemu_selftest/gen_expected.py -- do not edit.\n")
        w("// Expected results computed on the host in exact rational arithmetic.\n")
        w("#pragma once\n#include <cstdint>\n\nnamespace maglev::selftest {\n\n")
        w("struct F32Case { std::uint32_t a, b, add, sub, mul, div, sqrt_abs_a, fma_ab_a, mul_then_add_a; };\n")
        w("struct F64Case { std::uint64_t a, b, add, mul, div, sqrt_abs_a; };\n")
        w("struct CvtCase { std::uint32_t int_bits, float_bits, truncated_back, check_truncation; };\n")
        w("struct I64Case { std::uint64_t a, b, product, quotient, remainder, a_shr17; };\n\n")
        w(f"inline constexpr int kFusedDiffersCount = {fused_differs};\n\n")
        w(f"inline constexpr F32Case kF32Cases[{len(f32_rows)}] = {{\n")
        for r in f32_rows:
            w("    {" + ", ".join(f"0x{v:08x}U" for v in r) + "},\n")
        w("};\n\n")
        w(f"inline constexpr F64Case kF64Cases[{len(f64_rows)}] = {{\n")
        for r in f64_rows:
            w("    {" + ", ".join(f"0x{v:016x}ULL" for v in r) + "},\n")
        w("};\n\n")
        w(f"inline constexpr CvtCase kCvtCases[{len(cvt_rows)}] = {{\n")
        for r in cvt_rows:
            w("    {" + ", ".join(f"0x{v:08x}U" for v in r) + "},\n")
        w("};\n\n")
        w(f"inline constexpr I64Case kI64Cases[{len(i64_rows)}] = {{\n")
        for r in i64_rows:
            w("    {" + ", ".join(f"0x{v:016x}ULL" for v in r) + "},\n")
        w("};\n\n")
        w("// Initial value of a .data array and the CRC-32 (zlib) of its bytes.\n")
        w("#define MAGLEV_SELFTEST_DATA_PATTERN \\\n    ")
        w(", ".join(f"0x{v:08x}U" for v in pattern))
        w("\n")
        w(f"inline constexpr std::uint32_t kDataPatternCrc32 = 0x{crc:08x}U;\n\n")
        w("}  // namespace maglev::selftest\n")


if __name__ == "__main__":
    main()
