// SPDX-License-Identifier: Apache-2.0
// Named id types, so a cane id is never passed where a wire id is expected.
#pragma once

#include <compare>
#include <cstdint>
#include <functional>

namespace vb {

// A strongly typed integer id. `Tag` only distinguishes the types.
template <typename Tag>
struct Id {
  int64_t value = 0;

  constexpr Id() = default;
  constexpr explicit Id(int64_t v) : value(v) {}
  constexpr auto operator<=>(const Id&) const = default;
};

using CaneId = Id<struct CaneIdTag>;
using WireId = Id<struct WireIdTag>;
using PostId = Id<struct PostIdTag>;
using CutId = Id<struct CutIdTag>;
using VineId = Id<struct VineIdTag>;

}  // namespace vb

template <typename Tag>
struct std::hash<vb::Id<Tag>> {
  size_t operator()(const vb::Id<Tag>& id) const noexcept { return std::hash<int64_t>{}(id.value); }
};
