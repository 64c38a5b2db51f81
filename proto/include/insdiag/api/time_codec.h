// Times between absl::Time (the knowledge base's values) and the API's
// google.protobuf.Timestamp, for every codec at the API's edge.
#pragma once

#include <absl/time/time.h>
#include <google/protobuf/timestamp.pb.h>

namespace insdiag::api {

// Nanoseconds kept; before the epoch the seconds round down, so that nanos
// stay in [0, 1e9) as the message requires.
google::protobuf::Timestamp TimestampOf(absl::Time time);
absl::Time TimeOf(const google::protobuf::Timestamp& timestamp);
// A request's time to the whole microsecond the database keeps
// (seconds·10⁶ + nanos/10³, as the stores have always read a Timestamp).
absl::Time MicrosecondTimeOf(const google::protobuf::Timestamp& timestamp);

}  // namespace insdiag::api
