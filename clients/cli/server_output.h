// What the server verbs share: failing with the contract's exit status,
// JSON output, aligned text tables, numbers and times for people.
#pragma once

#include <absl/status/status.h>
#include <google/protobuf/message.h>
#include <google/protobuf/timestamp.pb.h>

#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "insdiag/client/run_client.h"
#include "insdiag/v1/knowledge.pb.h"
#include "verb.h"

namespace insdiag::cli {

// --server, --token and --ca-file, as every verb that talks to the server
// takes them.
struct ServerFlags {
  std::string address = client::kDefaultServerAddress;
  std::string token;
  std::string ca_file;
  void Declare(OptionSink& options);
  // An unreadable --ca-file ends the program with the usage status: nothing
  // may go to the server in clear when the user asked for TLS.
  std::shared_ptr<grpc::Channel> Connect() const;
};

// "insdiag VERB: WHAT: CODE: message" on `err`; returns kExitRefused.
int RequestFailed(std::ostream& err, const std::string& verb, const std::string& what, const absl::Status& status);
// "insdiag VERB: message" on `err`; returns kExitUsage.
int UsageError(std::ostream& err, const std::string& verb, const std::string& message);

// The message as pretty JSON (protobuf's JSON mapping); kExitOk or kExitRefused.
int PrintJson(const google::protobuf::Message& message, std::ostream& out, std::ostream& err);

// Left-aligned text columns, right-aligned numbers.
class Table {
 public:
  explicit Table(std::vector<std::string> header) : rows_{std::move(header)} {}
  void Add(std::vector<std::string> row) { rows_.push_back(std::move(row)); }
  void Print(std::ostream& out) const;

 private:
  std::vector<std::vector<std::string>> rows_;
};

std::string Number(double value, int significant = 4);  // "%.4g"
std::string Percent(double share);                       // "12.3 %"
std::string Date(const google::protobuf::Timestamp& t);  // "2024-03-01"
std::string DateTime(const google::protobuf::Timestamp& t);

// Optional numeric option text: nullopt when empty; an error when not a number.
absl::Status ParseInt(const std::string& text, const std::string& flag, int* value);
absl::Status ParseDouble(const std::string& text, const std::string& flag, double* value);

// The diagnosis's candidates (probability, module, mode) with their evidence,
// and its notes and resolution.
void PrintDiagnosisText(const v1::Diagnosis& diagnosis, std::ostream& out);

// "units/X" from "X" or "units/X"; likewise for other collections.
std::string ResourceName(const std::string& collection, const std::string& id_or_name);

}  // namespace insdiag::cli
