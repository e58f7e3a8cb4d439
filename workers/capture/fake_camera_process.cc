// SPDX-License-Identifier: Apache-2.0
#include "workers/capture/fake_camera_process.h"

#include <arpa/inet.h>
#include <arv.h>
#include <fcntl.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <regex>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"

namespace vb::capture::fake_gv {
namespace {

constexpr char kFakeCameraExe[] = "arv-fake-gv-camera-0.8";
constexpr uint16_t kGvcpPort = 3956;

std::string Errno(const char* what) { return absl::StrCat(what, ": ", std::strerror(errno)); }

class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

// Resolves `exe` along PATH before fork, so the child only calls async-signal-safe functions.
std::string FindOnPath(const std::string& exe) {
  const char* path = std::getenv("PATH");
  std::string dirs = path != nullptr ? path : "/usr/bin:/bin";
  size_t start = 0;
  while (start <= dirs.size()) {
    size_t end = dirs.find(':', start);
    if (end == std::string::npos) end = dirs.size();
    std::string candidate = absl::StrCat(dirs.substr(start, end - start), "/", exe);
    if (access(candidate.c_str(), X_OK) == 0) return candidate;
    start = end + 1;
  }
  return "";
}

}  // namespace

absl::Status EnterPrivateLoopbackNetwork(int n_addresses) {
  if (n_addresses < 1 || n_addresses > 254) {
    return absl::InvalidArgumentError("n_addresses: must be in [1, 254]");
  }
  if (unshare(CLONE_NEWNET) != 0) {
    return absl::PermissionDeniedError(Errno("unshare(CLONE_NEWNET)"));
  }
  Fd sock(socket(AF_INET, SOCK_DGRAM, 0));
  if (sock.get() < 0) return absl::InternalError(Errno("socket"));
  ifreq request{};
  std::strncpy(request.ifr_name, "lo", IFNAMSIZ - 1);
  if (ioctl(sock.get(), SIOCGIFFLAGS, &request) != 0) {
    return absl::InternalError(Errno("SIOCGIFFLAGS lo"));
  }
  request.ifr_flags |= IFF_UP;
  if (ioctl(sock.get(), SIOCSIFFLAGS, &request) != 0) {
    return absl::InternalError(Errno("SIOCSIFFLAGS lo up"));
  }
  // Bringing lo up assigns 127.0.0.1/8; the others become labelled aliases lo:2, lo:3, ...
  for (int i = 2; i <= n_addresses; ++i) {
    ifreq alias{};
    const std::string label = absl::StrCat("lo:", i);
    std::strncpy(alias.ifr_name, label.c_str(), IFNAMSIZ - 1);
    auto* address = reinterpret_cast<sockaddr_in*>(&alias.ifr_addr);
    address->sin_family = AF_INET;
    inet_pton(AF_INET, absl::StrCat("127.0.0.", i).c_str(), &address->sin_addr);
    if (ioctl(sock.get(), SIOCSIFADDR, &alias) != 0) {
      return absl::InternalError(Errno(absl::StrCat("SIOCSIFADDR ", label).c_str()));
    }
    auto* mask = reinterpret_cast<sockaddr_in*>(&alias.ifr_netmask);
    mask->sin_family = AF_INET;
    inet_pton(AF_INET, "255.0.0.0", &mask->sin_addr);
    if (ioctl(sock.get(), SIOCSIFNETMASK, &alias) != 0) {
      return absl::InternalError(Errno(absl::StrCat("SIOCSIFNETMASK ", label).c_str()));
    }
  }
  return absl::OkStatus();
}

bool IsInterfaceAddress(const std::string& ipv4) {
  in_addr wanted{};
  if (inet_pton(AF_INET, ipv4.c_str(), &wanted) != 1) return false;
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return false;
  bool found = false;
  for (ifaddrs* it = list; it != nullptr && !found; it = it->ifa_next) {
    if (it->ifa_addr == nullptr || it->ifa_addr->sa_family != AF_INET) continue;
    found = reinterpret_cast<sockaddr_in*>(it->ifa_addr)->sin_addr.s_addr == wanted.s_addr;
  }
  freeifaddrs(list);
  return found;
}

absl::Status WriteFakeGenicamWithout(const std::vector<std::string>& removed_formats,
                                     const std::string& path) {
  ArvFakeCamera* fake = arv_fake_camera_new("GENICAM");
  if (fake == nullptr) return absl::InternalError("arv_fake_camera_new failed");
  size_t size = 0;
  const char* xml_data = arv_fake_camera_get_genicam_xml(fake, &size);
  std::string xml = xml_data != nullptr ? std::string(xml_data, size) : std::string();
  g_object_unref(fake);
  if (xml.empty()) return absl::InternalError("the fake camera has no GenICam XML");
  for (const std::string& format : removed_formats) {
    const std::regex entry("\\s*<EnumEntry Name=\"" + format + "\"[^>]*>[\\s\\S]*?</EnumEntry>");
    std::string edited = std::regex_replace(xml, entry, "");
    if (edited == xml) {
      return absl::NotFoundError(absl::StrCat("no EnumEntry ", format, " in the fake's XML"));
    }
    xml = std::move(edited);
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << xml;
  out.close();
  if (!out) return absl::InternalError(absl::StrCat("cannot write ", path));
  return absl::OkStatus();
}

bool GvcpAnswers(const std::string& ipv4, absl::Duration timeout) {
  sockaddr_in device{};
  device.sin_family = AF_INET;
  device.sin_port = htons(kGvcpPort);
  if (inet_pton(AF_INET, ipv4.c_str(), &device.sin_addr) != 1) return false;
  Fd sock(socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0));
  if (sock.get() < 0) return false;
  if (connect(sock.get(), reinterpret_cast<sockaddr*>(&device), sizeof(device)) != 0) return false;
  // GVCP READREG_CMD of the version register (0x0000): key 0x42, flags 0x01 (ack required),
  // command 0x0080, length 4, request id; then the address. The answer is READREG_ACK 0x0081.
  const std::array<uint8_t, 12> command = {0x42, 0x01, 0x00, 0x80, 0x00, 0x04,
                                           0x12, 0x34, 0x00, 0x00, 0x00, 0x00};
  if (send(sock.get(), command.data(), command.size(), 0) != static_cast<ssize_t>(command.size())) {
    return false;
  }
  const absl::Time deadline = absl::Now() + timeout;
  while (true) {
    const int wait_ms = static_cast<int>(absl::ToInt64Milliseconds(deadline - absl::Now()));
    if (wait_ms <= 0) return false;
    pollfd poll_fd{sock.get(), POLLIN, 0};
    if (poll(&poll_fd, 1, wait_ms) <= 0) return false;
    std::array<uint8_t, 64> answer{};
    const ssize_t n = recv(sock.get(), answer.data(), answer.size(), 0);
    if (n < 0) return false;  // e.g. ECONNREFUSED: nothing listens yet
    if (n >= 8 && answer[2] == 0x00 && answer[3] == 0x81 && answer[6] == 0x12 &&
        answer[7] == 0x34) {
      return true;
    }
  }
}

absl::StatusOr<std::unique_ptr<FakeCameraProcess>> FakeCameraProcess::Start(Options options) {
  const std::string exe = FindOnPath(kFakeCameraExe);
  if (exe.empty()) {
    return absl::NotFoundError(absl::StrCat(kFakeCameraExe, " not found on PATH (aravis-tools)"));
  }
  std::vector<std::string> args = {exe, "-i", options.address, "-s", options.serial};
  if (!options.genicam_path.empty()) {
    args.push_back("-g");
    args.push_back(options.genicam_path);
  }
  if (options.gvsp_lost_per_thousand > 0) {
    args.push_back("-r");
    args.push_back(std::to_string(options.gvsp_lost_per_thousand));
  }
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);

  std::unique_ptr<FakeCameraProcess> process(new FakeCameraProcess(options));
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) return absl::InternalError(Errno("fork"));
  if (pid == 0) {
    // Child: async-signal-safe calls only. Die with the test process, never outlive it.
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(127);
    const int null_fd = open("/dev/null", O_RDWR);
    if (null_fd >= 0) {
      dup2(null_fd, STDIN_FILENO);
      dup2(null_fd, STDOUT_FILENO);
      dup2(null_fd, STDERR_FILENO);
    }
    execv(argv[0], argv.data());
    _exit(127);
  }
  process->pid_ = pid;

  const absl::Time deadline = absl::Now() + options.ready_timeout;
  while (true) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) {
      process->pid_ = -1;
      return absl::FailedPreconditionError(absl::StrCat(
          kFakeCameraExe, " on ", options.address, " exited early (status ", status,
          "); is the address assigned to an interface and port 3956 free?"));
    }
    if (GvcpAnswers(options.address, absl::Milliseconds(100))) return process;
    if (absl::Now() >= deadline) {
      process->Kill();
      return absl::DeadlineExceededError(absl::StrCat(kFakeCameraExe, " on ", options.address,
                                                      " did not answer within ",
                                                      absl::FormatDuration(options.ready_timeout)));
    }
    absl::SleepFor(absl::Milliseconds(20));
  }
}

FakeCameraProcess::~FakeCameraProcess() { Kill(); }

void FakeCameraProcess::Kill() {
  if (pid_ <= 0) return;
  kill(pid_, SIGKILL);
  int status = 0;
  while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
  }
  pid_ = -1;
}

}  // namespace vb::capture::fake_gv
