// SPDX-License-Identifier: Apache-2.0
#include "app/flags.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "absl/strings/str_cat.h"

namespace vb::app {

absl::StatusOr<Flags> Flags::Parse(int argc, char** argv, int first) {
  Flags flags;
  for (int i = first; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg.rfind("--", 0) != 0 || arg.size() == 2) {
      return absl::InvalidArgumentError(absl::StrCat("unexpected argument '", arg, "'"));
    }
    arg = arg.substr(2);
    const size_t eq = arg.find('=');
    if (eq != std::string::npos) {
      flags.values_[arg.substr(0, eq)] = arg.substr(eq + 1);
    } else if (i + 1 < argc && std::string(argv[i + 1]).rfind("--", 0) != 0) {
      flags.values_[arg] = argv[++i];
    } else {
      flags.values_[arg] = std::nullopt;
    }
  }
  return flags;
}

bool Flags::Has(const std::string& name) {
  read_.insert(name);
  return values_.contains(name);
}

absl::StatusOr<std::string> Flags::String(const std::string& name, const std::string& fallback) {
  read_.insert(name);
  auto it = values_.find(name);
  if (it == values_.end()) return fallback;
  if (!it->second.has_value()) return absl::InvalidArgumentError(absl::StrCat("--", name, ": needs a value"));
  return *it->second;
}

absl::StatusOr<std::string> Flags::RequiredString(const std::string& name) {
  read_.insert(name);
  if (!values_.contains(name)) return absl::InvalidArgumentError(absl::StrCat("--", name, ": required"));
  return String(name, "");
}

absl::StatusOr<double> Flags::Double(const std::string& name, double fallback) {
  auto s = String(name, "");
  if (!s.ok()) return s.status();
  if (!values_.contains(name)) return fallback;
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s->c_str(), &end);
  if (s->empty() || *end != '\0' || errno != 0 || !std::isfinite(v)) {
    return absl::InvalidArgumentError(absl::StrCat("--", name, ": '", *s, "' is not a number"));
  }
  return v;
}

absl::StatusOr<int64_t> Flags::Int(const std::string& name, int64_t fallback) {
  auto s = String(name, "");
  if (!s.ok()) return s.status();
  if (!values_.contains(name)) return fallback;
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(s->c_str(), &end, 10);
  if (s->empty() || *end != '\0' || errno != 0) {
    return absl::InvalidArgumentError(absl::StrCat("--", name, ": '", *s, "' is not an integer"));
  }
  return static_cast<int64_t>(v);
}

absl::StatusOr<bool> Flags::Bool(const std::string& name, bool fallback) {
  read_.insert(name);
  auto it = values_.find(name);
  if (it == values_.end()) return fallback;
  if (!it->second.has_value()) return true;
  const std::string& v = *it->second;
  if (v == "true" || v == "1") return true;
  if (v == "false" || v == "0") return false;
  return absl::InvalidArgumentError(absl::StrCat("--", name, ": '", v, "' is not true or false"));
}

absl::StatusOr<PixelFormat> Flags::Format(const std::string& name, PixelFormat fallback) {
  auto s = String(name, std::string(PixelFormatName(fallback)));
  if (!s.ok()) return s.status();
  auto format = ParsePixelFormat(*s);
  if (!format.ok()) {
    return absl::InvalidArgumentError(
        absl::StrCat("--", name, ": ", std::string(format.status().message())));
  }
  return *format;
}

absl::Status Flags::Finish() const {
  std::string unknown;
  for (const auto& [name, value] : values_) {
    if (!read_.contains(name)) absl::StrAppend(&unknown, unknown.empty() ? "" : ", ", "--", name);
  }
  if (!unknown.empty()) return absl::InvalidArgumentError(absl::StrCat("unknown flag(s): ", unknown));
  return absl::OkStatus();
}

}  // namespace vb::app
