// SPDX-License-Identifier: Apache-2.0
// A point in time after which long computations give up, plus an optional cancellation flag
// that job cancellation (and later gRPC cancellation) sets. Long stages poll Expired() between
// units of work and return DEADLINE_EXCEEDED (or CANCELLED) with what they finished.
// Copyable; Expired() is thread-safe (the flag is atomic and owned by the caller, who must keep
// it alive for as long as any copy of the deadline is used).
#pragma once

#include <atomic>
#include <chrono>
#include <limits>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace vb {

class Deadline {
 public:
  using Clock = std::chrono::steady_clock;

  // Never expires.
  static Deadline Infinite() { return Deadline(Clock::time_point::max(), nullptr); }
  // Expires `seconds` from now; a non-finite or huge value means never.
  static Deadline In(double seconds, const std::atomic<bool>* cancelled = nullptr) {
    if (!(seconds < 1e9)) return Deadline(Clock::time_point::max(), cancelled);
    const auto delta = std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(seconds < 0 ? 0.0 : seconds));
    return Deadline(Clock::now() + delta, cancelled);
  }

  bool Cancelled() const { return cancelled_ != nullptr && cancelled_->load(); }
  bool Expired() const { return Cancelled() || (at_ != Clock::time_point::max() && Clock::now() >= at_); }
  // Seconds left (infinity if none is set; 0 once expired).
  double RemainingS() const {
    if (at_ == Clock::time_point::max()) return std::numeric_limits<double>::infinity();
    const double s = std::chrono::duration<double>(at_ - Clock::now()).count();
    return s > 0 ? s : 0.0;
  }
  // OK while time is left; CANCELLED or DEADLINE_EXCEEDED naming `what` once it is not.
  absl::Status Check(const char* what) const {
    if (Cancelled()) return absl::CancelledError(absl::StrCat(what, ": cancelled"));
    if (Expired()) return absl::DeadlineExceededError(absl::StrCat(what, ": deadline exceeded"));
    return absl::OkStatus();
  }

 private:
  Deadline(Clock::time_point at, const std::atomic<bool>* cancelled)
      : at_(at), cancelled_(cancelled) {}
  Clock::time_point at_;
  const std::atomic<bool>* cancelled_;
};

}  // namespace vb
