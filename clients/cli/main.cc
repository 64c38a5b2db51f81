// insdiag — the command line. Builds one subcommand per registered verb
// (verbs.inc) and runs the chosen one. Exit status: 0 ok, 1 refused input or
// failed request, 2 bad usage.
#include <CLI/CLI.hpp>

#include <iostream>

#include "verb.h"

namespace insdiag::cli {
namespace {

// Declares a verb's options on its CLI11 subcommand.
class Cli11Options final : public OptionSink {
 public:
  explicit Cli11Options(CLI::App& command) : command_(command) {}
  void Positional(const std::string& name, std::string* value, const std::string& help) override {
    command_.add_option(name, *value, help)->required();
  }
  void Positionals(const std::string& name, std::vector<std::string>* values, const std::string& help) override {
    command_.add_option(name, *values, help);
  }
  void Option(const std::string& flag, std::string* value, const std::string& help, const std::string& env) override {
    auto* option = command_.add_option(flag, *value, help);
    if (!env.empty()) option->envname(env);
  }
  void Repeated(const std::string& flag, std::vector<std::string>* values, const std::string& help) override {
    command_.add_option(flag, *values, help);
  }
  void Flag(const std::string& flag, bool* value, const std::string& help) override {
    command_.add_flag(flag, *value, help);
  }

 private:
  CLI::App& command_;
};

int Main(int argc, char** argv) {
  CLI::App app{"insdiag — diagnosis of inertial navigation systems from bench tests"};
  app.require_subcommand(1);
  auto verbs = AllVerbs();
  std::vector<std::pair<CLI::App*, Verb*>> commands;
  for (auto& verb : verbs) {
    CLI::App* command = app.add_subcommand(verb->Name(), verb->Summary());
    Cli11Options options(*command);
    verb->DeclareOptions(options);
    commands.emplace_back(command, verb.get());
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& help) {
    return app.exit(help);
  } catch (const CLI::CallForAllHelp& help) {
    return app.exit(help);
  } catch (const CLI::ParseError& error) {
    app.exit(error);
    return kExitUsage;
  }
  for (auto& [command, verb] : commands) {
    if (command->parsed()) return verb->Run(std::cout, std::cerr);
  }
  return kExitUsage;
}

}  // namespace
}  // namespace insdiag::cli

int main(int argc, char** argv) { return insdiag::cli::Main(argc, argv); }
