// SPDX-License-Identifier: Apache-2.0
// Placeholder while the command is being written this session; replaced before the issue closes.
#include "app/commands.h"

namespace vb::app {

absl::Status RunBenchReconstruct(Flags&) { return absl::UnimplementedError("not built yet"); }

}  // namespace vb::app
