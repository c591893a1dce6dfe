#pragma once
// Each subcommand lives in its own apps/cmd_*.cpp and registers itself here, so adding a
// command touches only its own file and apps/CMakeLists.txt.

#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace meshflow::apps {

// Adds the subcommand to `app`; the callback it sets returns the process's exit status
// through `exit_status`. Errors are thrown (InvalidInput/ParseError -> 2, others -> 1).
using CommandFactory = std::function<void(CLI::App& app, int& exit_status)>;

struct CommandRegistration {
  CommandRegistration(std::string name, CommandFactory factory);
};
std::vector<std::pair<std::string, CommandFactory>>& command_registry();

}  // namespace meshflow::apps

#define MESHFLOW_COMMAND(name, factory) \
  static const ::meshflow::apps::CommandRegistration meshflow_command_##name{#name, factory}
