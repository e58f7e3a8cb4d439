// SPDX-License-Identifier: Apache-2.0
// A minimal command-line flag parser for the vinebot subcommands: `--name value`, `--name=value`
// and boolean `--name`. Every flag a command reads is declared by reading it; Finish() then
// rejects any flag given but never read, so typos are errors, not silently ignored.
// Not thread-safe.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/image.h"

namespace vb::app {

class Flags {
 public:
  // Parses argv[first..argc). INVALID_ARGUMENT for a positional argument or an empty name.
  static absl::StatusOr<Flags> Parse(int argc, char** argv, int first);

  // Typed getters: the flag's value, or `fallback` when absent. INVALID_ARGUMENT naming the flag
  // when the value does not parse.
  absl::StatusOr<std::string> String(const std::string& name, const std::string& fallback);
  absl::StatusOr<std::string> RequiredString(const std::string& name);
  absl::StatusOr<double> Double(const std::string& name, double fallback);
  absl::StatusOr<int64_t> Int(const std::string& name, int64_t fallback);
  // `--name`, `--name=true|false|1|0`.
  absl::StatusOr<bool> Bool(const std::string& name, bool fallback);
  bool Has(const std::string& name);
  // A vinebot pixel format name (rgb8, mono8, bayer_rg8, ...).
  absl::StatusOr<PixelFormat> Format(const std::string& name, PixelFormat fallback);

  // INVALID_ARGUMENT listing flags that were given but not read by the command.
  absl::Status Finish() const;

 private:
  std::map<std::string, std::optional<std::string>> values_;
  std::set<std::string> read_;
};

}  // namespace vb::app
