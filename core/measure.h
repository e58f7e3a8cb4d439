// SPDX-License-Identifier: Apache-2.0
// Helpers for benchmarks and diagnostics: the calling thread's CPU time (steadier than wall time on
// a shared machine) and FNV-1a fingerprints over the bytes of values, to show that two builds
// produce the same results bit for bit. Thread-safe (pure, or per-thread clocks).
#pragma once

#include <time.h>

#include <cstdint>
#include <cstring>
#include <type_traits>

namespace vb {

// CPU time used by the calling thread, seconds (CLOCK_THREAD_CPUTIME_ID).
inline double ThreadCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// FNV-1a's offset basis: the fingerprint of nothing.
inline constexpr uint64_t kFnv1aOffset = 1469598103934665603ull;

// FNV-1a (Fowler, Noll, Vo) of `h` continued over the bytes of `value` (a trivially copyable
// value: its bits, so 0.0 and -0.0 differ).
template <typename T>
uint64_t Fnv1a(const T& value, uint64_t h = kFnv1aOffset) {
  static_assert(std::is_trivially_copyable_v<T>);
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  for (unsigned char b : bytes) h = (h ^ b) * 1099511628211ull;
  return h;
}

}  // namespace vb
