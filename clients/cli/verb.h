// A verb of the `insdiag` command line. Each verb lives in its own file,
// cli/verbs/<name>.cc, defines `std::unique_ptr<Verb> MakeVerb_<name>()` and
// is registered by one line INSDIAG_VERB(<name>) in cli/verbs.inc. Verbs
// declare their options through OptionSink, so that only main.cc includes
// the (slow to compile) argument parser.
#pragma once

#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

namespace insdiag::cli {

// Exit statuses of the command-line contract (shared/spec/cli-and-report.md).
inline constexpr int kExitOk = 0;
inline constexpr int kExitRefused = 1;  // refused input or failed request; the reason on stderr
inline constexpr int kExitUsage = 2;

class OptionSink {
 public:
  virtual ~OptionSink() = default;
  // A required positional argument, e.g. "RUN.csv".
  virtual void Positional(const std::string& name, std::string* value, const std::string& help) = 0;
  // Optional positional arguments, e.g. "ACTION ARGS": all that remain.
  virtual void Positionals(const std::string& name, std::vector<std::string>* values, const std::string& help) = 0;
  // "--server" with a value; `env` names an environment variable that
  // supplies the default when set.
  virtual void Option(const std::string& flag, std::string* value, const std::string& help,
                      const std::string& env = "") = 0;
  virtual void Repeated(const std::string& flag, std::vector<std::string>* values, const std::string& help) = 0;
  virtual void Flag(const std::string& flag, bool* value, const std::string& help) = 0;
};

class Verb {
 public:
  virtual ~Verb() = default;
  virtual std::string Name() const = 0;
  virtual std::string Summary() const = 0;
  virtual void DeclareOptions(OptionSink& options) = 0;
  // Runs with the parsed options; returns the exit status.
  virtual int Run(std::ostream& out, std::ostream& err) = 0;
};

#define INSDIAG_VERB(name) std::unique_ptr<Verb> MakeVerb_##name();
#include "verbs.inc"
#undef INSDIAG_VERB

// Every registered verb, in verbs.inc order.
inline std::vector<std::unique_ptr<Verb>> AllVerbs() {
  std::vector<std::unique_ptr<Verb>> verbs;
#define INSDIAG_VERB(name) verbs.push_back(MakeVerb_##name());
#include "verbs.inc"
#undef INSDIAG_VERB
  return verbs;
}

}  // namespace insdiag::cli
