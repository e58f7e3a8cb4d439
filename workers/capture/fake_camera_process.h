// SPDX-License-Identifier: Apache-2.0
// Test helpers: Aravis' fake GigE Vision camera (arv-fake-gv-camera-0.8, package aravis-tools) as a
// child process, and a private loopback network to run several of them.
//
// GigE Vision control (GVCP) uses the fixed UDP port 3956, so several fake cameras need several
// addresses, and the fake camera only listens on an address assigned to an interface. On Linux
// 127.0.0.0/8 routes to lo but only 127.0.0.1 is assigned; EnterPrivateLoopbackNetwork() gives the
// process its own network namespace (so nothing of the host's network changes, and parallel test
// processes cannot collide on port 3956) with 127.0.0.2, 127.0.0.3, ... added to its lo.
#pragma once

#include <sys/types.h>

#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/time/time.h"

namespace vb::capture::fake_gv {

// Moves the calling thread into a new network namespace (unshare(CLONE_NEWNET); needs
// CAP_SYS_ADMIN), brings lo up and assigns 127.0.0.1 ... 127.0.0.<n_addresses>. Threads and
// children created afterwards inherit it, so call this from the main thread before any Aravis
// use. PERMISSION_DENIED if the sandbox forbids it (the caller may fall back to the host's lo).
absl::Status EnterPrivateLoopbackNetwork(int n_addresses);

// Whether `ipv4` is assigned to a local interface (the fake camera can listen on it).
bool IsInterfaceAddress(const std::string& ipv4);

// Writes the fake camera's built-in GenICam XML to `path` without the PixelFormat entries named in
// `removed_formats` (PFNC names, e.g. "RGB8"): a fake device that lacks those formats.
absl::Status WriteFakeGenicamWithout(const std::vector<std::string>& removed_formats,
                                     const std::string& path);

// One arv-fake-gv-camera-0.8 child process. Not thread-safe.
class FakeCameraProcess {
 public:
  struct Options {
    std::string address = "127.0.0.1";  // -i: the interface address it listens on
    std::string serial = "VB0001";      // -s: DeviceID becomes "Aravis-Fake-<serial>"
    std::string genicam_path;           // -g: GenICam XML; empty for the built-in one
    int gvsp_lost_per_thousand = 0;     // -r: stream packets dropped per thousand
    absl::Duration ready_timeout = absl::Seconds(5);
  };

  // Spawns the process (stdout/stderr to /dev/null; killed if this process dies) and waits until
  // it answers a GVCP register read. FAILED_PRECONDITION if it exits early (address not on an
  // interface, port in use); DEADLINE_EXCEEDED if it does not answer within ready_timeout;
  // NOT_FOUND if the executable is missing. Never leaves a process behind on failure.
  static absl::StatusOr<std::unique_ptr<FakeCameraProcess>> Start(Options options);

  ~FakeCameraProcess();  // Kill()
  FakeCameraProcess(const FakeCameraProcess&) = delete;
  FakeCameraProcess& operator=(const FakeCameraProcess&) = delete;

  // SIGKILL and reap; idempotent.
  void Kill();
  bool running() const { return pid_ > 0; }
  pid_t pid() const { return pid_; }
  const std::string& address() const { return options_.address; }
  // The device id Aravis reports ("Aravis-Fake-<serial>").
  std::string device_id() const { return "Aravis-Fake-" + options_.serial; }

 private:
  explicit FakeCameraProcess(Options options) : options_(std::move(options)) {}
  Options options_;
  pid_t pid_ = -1;
};

// Whether something answers GVCP on `ipv4`:3956 within `timeout`.
bool GvcpAnswers(const std::string& ipv4, absl::Duration timeout);

}  // namespace vb::capture::fake_gv
