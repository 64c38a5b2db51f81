// Early return on an error status, for functions whose steps each may fail:
//
//   INSDIAG_RETURN_IF_ERROR(store.Check(request));          // an absl::Status or StatusOr
//   INSDIAG_ASSIGN_OR_RETURN(auto rows, db->Exec(sql, params));  // rows: the value
//
// Each returns the failing step's status unchanged, so a caller sees the
// error the step gave (its code and its message naming the field or row).
// Used where ok()-and-return chains dominate a function; code whose steps
// decide on an error (retry, fall back, note it) tests ok() itself.
#pragma once

#include <absl/status/status.h>
#include <absl/status/statusor.h>

#include <utility>

namespace insdiag::internal {

inline const absl::Status& StatusOf(const absl::Status& status) { return status; }
template <typename T>
const absl::Status& StatusOf(const absl::StatusOr<T>& value) {
  return value.status();
}

}  // namespace insdiag::internal

#define INSDIAG_STATUS_CONCAT_INNER(a, b) a##b
#define INSDIAG_STATUS_CONCAT(a, b) INSDIAG_STATUS_CONCAT_INNER(a, b)

#define INSDIAG_RETURN_IF_ERROR(...)                                          \
  do {                                                                        \
    if (const auto& insdiag_status_ = (__VA_ARGS__); !insdiag_status_.ok()) { \
      return ::insdiag::internal::StatusOf(insdiag_status_);                  \
    }                                                                         \
  } while (false)

#define INSDIAG_ASSIGN_OR_RETURN(lhs, ...)                                               \
  INSDIAG_ASSIGN_OR_RETURN_IMPL(INSDIAG_STATUS_CONCAT(insdiag_statusor_, __LINE__), lhs, \
                                __VA_ARGS__)

#define INSDIAG_ASSIGN_OR_RETURN_IMPL(statusor, lhs, ...)  \
  auto statusor = (__VA_ARGS__);                           \
  if (!statusor.ok()) return std::move(statusor).status(); \
  lhs = *std::move(statusor)
