// SPDX-License-Identifier: Apache-2.0
// Propagation helpers for absl::Status / absl::StatusOr, used across every vinebot library.
#pragma once

#include "absl/status/status.h"
#include "absl/status/statusor.h"

#define VB_STATUS_CONCAT_INNER_(a, b) a##b
#define VB_STATUS_CONCAT_(a, b) VB_STATUS_CONCAT_INNER_(a, b)

// Returns from the current function if `expr` (an absl::Status) is not OK.
#define VB_RETURN_IF_ERROR(expr)                  \
  do {                                            \
    const ::absl::Status vb_status_ = (expr);     \
    if (!vb_status_.ok()) return vb_status_;      \
  } while (false)

// VB_ASSIGN_OR_RETURN(auto x, MakeX()); returns the error status if MakeX() failed.
#define VB_ASSIGN_OR_RETURN(lhs, expr) \
  VB_ASSIGN_OR_RETURN_IMPL_(VB_STATUS_CONCAT_(vb_statusor_, __LINE__), lhs, expr)
#define VB_ASSIGN_OR_RETURN_IMPL_(tmp, lhs, expr) \
  auto tmp = (expr);                              \
  if (!tmp.ok()) return tmp.status();             \
  lhs = std::move(tmp).value()
