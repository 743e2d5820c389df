// Deterministic noise source of the plant: one 64-bit Mersenne twister,
// seeded once; every draw happens in a fixed order per tick, so a run is
// reproducible from (config, seed, command sequence).
//
// Normal draws (issue 16 item 5): a 256-layer ziggurat (Marsaglia & Tsang
// 2000, the symmetric form of Doornik 2005 / rand_distr) on xoshiro256++
// seeded from the same seed, one 64-bit word per draw in 98.8 % of draws
// (host instructions per draw: see docs/PERFORMANCE.md; std::normal_distribution's
// polar method on mt19937_64 costs ~120, 27 draws per bench tick).
// It is an exact sampler of N(0, 1) (rejection outside the layers' cores and
// Marsaglia's tail method beyond R), so the noise statistics are those of
// the polar method; the realization of a seed is not. NormalMethod::kPolar
// keeps std::normal_distribution (the sequence every run had before), for
// the pinned pre-issue-15 plant digests and the classic-integrator golden.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>

namespace maglev::hil {

enum class NormalMethod { kZiggurat, kPolar };

namespace detail {
// Layer edges x[0..256] and densities f[i] = exp(-x[i]^2 / 2) of the
// 256-layer ziggurat: x[1] = R is where the tail starts, every layer (and
// the base: the strip under f beyond R plus the rectangle R x f(R)) has the
// area V; x[0] = V / f(R) is the base's width as a rectangle, x[256] = 0.
struct ZigguratTables {
  static constexpr std::size_t kLayers = 256;
  static constexpr double kR = 3.6541528853610088;
  static constexpr double kV = 0.00492867323399;  // area of each layer (unnormalized density)
  std::array<double, kLayers + 1> x{};
  std::array<double, kLayers + 1> f{};
  ZigguratTables() {
    const auto pdf = [](double v) { return std::exp(-0.5 * v * v); };
    x[0] = kV / pdf(kR);
    x[1] = kR;
    for (std::size_t i = 1; i < kLayers - 1; ++i) x[i + 1] = std::sqrt(-2.0 * std::log(kV / x[i] + pdf(x[i])));
    x[kLayers] = 0.0;
    for (std::size_t i = 0; i <= kLayers; ++i) f[i] = pdf(x[i]);
  }
};
inline const ZigguratTables& ziggurat_tables() {
  static const ZigguratTables t;
  return t;
}
}  // namespace detail

class Rng {
 public:
  explicit Rng(std::uint64_t seed, NormalMethod method = NormalMethod::kZiggurat)
      : engine_(seed), method_(method), zig_(detail::ziggurat_tables()) {
    // xoshiro256++'s state from the seed by splitmix64 (Vigna's seeding).
    std::uint64_t z = seed;
    for (std::uint64_t& w : xs_) {
      z += 0x9e3779b97f4a7c15ull;
      std::uint64_t m = z;
      m = (m ^ (m >> 30)) * 0xbf58476d1ce4e5b9ull;
      m = (m ^ (m >> 27)) * 0x94d049bb133111ebull;
      w = m ^ (m >> 31);
    }
  }
  // Standard normal sample.
  double Normal() { return method_ == NormalMethod::kZiggurat ? Ziggurat() : normal_(engine_); }
  double Uniform() { return uniform_(engine_); }
  NormalMethod method() const { return method_; }

 private:
  // xoshiro256++ (Blackman & Vigna 2019): the ziggurat's word source, ~10
  // instructions a word against mt19937_64's ~40 (its refill amortized).
  static std::uint64_t Rotl(std::uint64_t v, int k) { return (v << k) | (v >> (64 - k)); }
  std::uint64_t Next() {
    const std::uint64_t result = Rotl(xs_[0] + xs_[3], 23) + xs_[0];
    const std::uint64_t t = xs_[1] << 17;
    xs_[2] ^= xs_[0];
    xs_[3] ^= xs_[1];
    xs_[1] ^= xs_[2];
    xs_[0] ^= xs_[3];
    xs_[2] ^= t;
    xs_[3] = Rotl(xs_[3], 45);
    return result;
  }
  // 53 random bits as a double (a signed conversion: one instruction).
  static double Bits53(std::uint64_t w) { return static_cast<double>(static_cast<std::int64_t>(w >> 11)); }
  // (0, 1]: never 0 (the tail takes its logarithm).
  double OpenUniform() { return (Bits53(Next()) + 1.0) * 0x1.0p-53; }

  // The fast path (98.8 % of draws) inline; the rest out of line, so the
  // common draw pays no register saves for the libm calls.
  double Ziggurat() {
    // One word: bits 0-7 choose the layer, bits 11-63 the signed abscissa
    // u in (-1, 1), symmetric about 0 (the half-LSB offset).
    const std::uint64_t bits = Next();
    const std::size_t i = static_cast<std::size_t>(bits & 0xFFu);
    const double u = (Bits53(bits) + 0.5) * 0x1.0p-52 - 1.0;
    const double x = u * zig_.x[i];
    if (std::fabs(x) < zig_.x[i + 1]) return x;  // inside the layer's core
    return ZigguratEdge(i, u, x);
  }

  [[gnu::noinline]] double ZigguratEdge(std::size_t i, double u, double x) {
    for (;;) {
      if (i == 0) {
        // The base beyond R: Marsaglia's tail method.
        double tx, ty;
        do {
          tx = std::log(OpenUniform()) / detail::ZigguratTables::kR;
          ty = std::log(OpenUniform());
        } while (-2.0 * ty < tx * tx);
        return u < 0.0 ? tx - detail::ZigguratTables::kR : detail::ZigguratTables::kR - tx;
      }
      // The wedge between the core and the density: accept under f.
      const double y = zig_.f[i] + (zig_.f[i + 1] - zig_.f[i]) * (Bits53(Next()) * 0x1.0p-53);
      if (y < std::exp(-0.5 * x * x)) return x;
      // Rejected: a new draw, as in Ziggurat().
      const std::uint64_t bits = Next();
      i = static_cast<std::size_t>(bits & 0xFFu);
      u = (Bits53(bits) + 0.5) * 0x1.0p-52 - 1.0;
      x = u * zig_.x[i];
      if (std::fabs(x) < zig_.x[i + 1]) return x;
    }
  }

  std::mt19937_64 engine_;  // polar draws and Uniform()
  std::uint64_t xs_[4];     // ziggurat draws
  NormalMethod method_;
  const detail::ZigguratTables& zig_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
};

}  // namespace maglev::hil
