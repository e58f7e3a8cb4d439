// SPDX-License-Identifier: Apache-2.0
// Portable random numbers for the vine generator. std::uniform_real_distribution and
// std::normal_distribution are implementation-defined, so a scene generated with libstdc++ would
// differ from one generated with libc++; these helpers use only the raw 64-bit output of
// std::mt19937_64 (whose sequence the standard fixes) and plain arithmetic, so a (seed, index)
// pair means the same vine everywhere (up to last-bit differences of libm's log/cos/sin).
// Not thread-safe: one VineRng per thread / per generated object.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

namespace vb::sim {

// SplitMix64 finaliser (Steele, Lea & Flood, "Fast splittable pseudorandom number generators",
// OOPSLA 2014): a bijective avalanche mix, used to derive independent stream seeds.
inline uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Seed of the random stream `stream` of the object `index` in the vineyard `seed`. Distinct
// (seed, index, stream) triples give unrelated streams.
inline uint64_t MixSeed(uint64_t seed, int64_t index, uint64_t stream) {
  uint64_t h = SplitMix64(seed ^ 0x5EED5EED5EED5EEDull);
  h = SplitMix64(h ^ static_cast<uint64_t>(index));
  return SplitMix64(h ^ (stream * 0xD1B54A32D192ED03ull));
}

class VineRng {
 public:
  explicit VineRng(uint64_t seed) : engine_(seed) {}

  uint64_t Next() { return engine_(); }
  // Uniform in [0, 1) with 53 random bits.
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  // Uniform integer in [lo, hi] (inclusive); lo <= hi. Plain modulo reduction: the bias is below
  // range / 2^64, nothing for the small ranges used here.
  int UniformInt(int lo, int hi) {
    const uint64_t range = static_cast<uint64_t>(static_cast<int64_t>(hi) - lo + 1);
    return lo + static_cast<int>(Next() % range);
  }
  bool Bernoulli(double p) { return Uniform() < p; }
  // Standard normal by the Box-Muller transform (one draw per call; no cached pair, so the
  // stream position depends only on the number of calls).
  double Normal() {
    const double u1 = 1.0 - Uniform();  // (0, 1]
    const double u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }
  double Normal(double mean, double sd) { return mean + sd * Normal(); }
  // +1 or -1 with equal probability.
  double Sign() { return (Next() >> 63) != 0 ? 1.0 : -1.0; }

 private:
  std::mt19937_64 engine_;
};

}  // namespace vb::sim
