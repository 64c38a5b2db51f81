#include "server_output.h"

#include <absl/strings/numbers.h>
#include <absl/strings/str_cat.h>
#include <absl/strings/str_format.h>
#include <absl/time/time.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>

#include "insdiag/api/json.h"
#include "verb.h"

namespace insdiag::cli {

void ServerFlags::Declare(OptionSink& options) {
  options.Option("--server", &address, "Server gRPC address host:port (default localhost:50051)", "INSDIAG_SERVER");
  options.Option("--token", &token, "Bearer token (insdiag tokens create; the first admin token is in the server's "
                 "data directory, admin-token)", "INSDIAG_TOKEN");
  options.Option("--ca-file", &ca_file, "PEM certificates to verify a TLS server against (default: plaintext)",
                 "INSDIAG_CA_FILE");
}

std::shared_ptr<grpc::Channel> ServerFlags::Connect() const {
  std::string ca_pem;
  if (!ca_file.empty()) {
    std::ifstream in(ca_file, std::ios::binary);
    std::ostringstream text;
    if (!in || !(text << in.rdbuf()) || text.str().find("-----BEGIN CERTIFICATE-----") == std::string::npos) {
      std::cerr << "insdiag: --ca-file " << ca_file << ": cannot read PEM certificates from it\n";
      std::exit(kExitUsage);
    }
    ca_pem = text.str();
  }
  return client::Connect(address, token, ca_pem);
}

int RequestFailed(std::ostream& err, const std::string& verb, const std::string& what, const absl::Status& status) {
  err << "insdiag " << verb << ": " << what << ": " << absl::StatusCodeToString(status.code()) << ": "
      << status.message() << "\n";
  return kExitRefused;
}

int UsageError(std::ostream& err, const std::string& verb, const std::string& message) {
  err << "insdiag " << verb << ": " << message << "\n";
  return kExitUsage;
}

int PrintJson(const google::protobuf::Message& message, std::ostream& out, std::ostream& err) {
  auto text = api::ToJson(message, /*pretty=*/true);
  if (!text.ok()) {
    err << "insdiag: cannot print JSON: " << text.status().message() << "\n";
    return kExitRefused;
  }
  out << *text << "\n";
  return kExitOk;
}

namespace {
bool Numeric(const std::string& cell) {
  if (cell.empty()) return false;
  const char c = cell.front();
  return std::isdigit(static_cast<unsigned char>(c)) || ((c == '-' || c == '+' || c == '.') && cell.size() > 1);
}
}  // namespace

void Table::Print(std::ostream& out) const {
  std::vector<std::size_t> width;
  for (const auto& row : rows_) {
    if (width.size() < row.size()) width.resize(row.size(), 0);
    for (std::size_t c = 0; c < row.size(); ++c) width[c] = std::max(width[c], row[c].size());
  }
  for (std::size_t r = 0; r < rows_.size(); ++r) {
    std::string line;
    for (std::size_t c = 0; c < rows_[r].size(); ++c) {
      const std::string& cell = rows_[r][c];
      const std::string pad(width[c] - cell.size(), ' ');
      if (c > 0) line += "  ";
      line += r > 0 && Numeric(cell) ? pad + cell : cell + (c + 1 < rows_[r].size() ? pad : "");
    }
    out << line << "\n";
  }
}

std::string Number(double value, int significant) { return absl::StrFormat("%.*g", significant, value); }

std::string Percent(double share) { return absl::StrFormat("%.1f %%", 100.0 * share); }

std::string Date(const google::protobuf::Timestamp& t) {
  return absl::FormatTime("%Y-%m-%d", absl::FromUnixSeconds(t.seconds()), absl::UTCTimeZone());
}

std::string DateTime(const google::protobuf::Timestamp& t) {
  return absl::FormatTime("%Y-%m-%d %H:%M:%S", absl::FromUnixSeconds(t.seconds()), absl::UTCTimeZone());
}

absl::Status ParseInt(const std::string& text, const std::string& flag, int* value) {
  if (text.empty()) return absl::OkStatus();
  if (!absl::SimpleAtoi(text, value)) return absl::InvalidArgumentError(absl::StrCat(flag, ": '", text, "' is not an integer"));
  return absl::OkStatus();
}

absl::Status ParseDouble(const std::string& text, const std::string& flag, double* value) {
  if (text.empty()) return absl::OkStatus();
  if (!absl::SimpleAtod(text, value)) return absl::InvalidArgumentError(absl::StrCat(flag, ": '", text, "' is not a number"));
  return absl::OkStatus();
}

void PrintDiagnosisText(const v1::Diagnosis& diagnosis, std::ostream& out) {
  for (const auto& c : diagnosis.candidates()) {
    if (c.probability() < 1e-4) continue;
    out << absl::StrFormat("%6.1f %%  %-16s %s\n", 100.0 * c.probability(), c.module(), c.failure_mode());
    for (const auto& line : c.evidence()) out << "           " << line << "\n";
  }
  for (const auto& note : diagnosis.notes()) out << "note: " << note << "\n";
  if (!diagnosis.failure_record().empty()) {
    out << "resolved: " << (diagnosis.confirmed() ? "confirmed" : "rejected (no fault found)") << " on "
        << diagnosis.resolved_module() << ", " << diagnosis.failure_record() << "\n";
  }
}

std::string ResourceName(const std::string& collection, const std::string& id_or_name) {
  if (id_or_name.empty() || id_or_name.starts_with(collection + "/")) return id_or_name;
  return absl::StrCat(collection, "/", id_or_name);
}

}  // namespace insdiag::cli
