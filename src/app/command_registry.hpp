#pragma once
// Subcommands register themselves (static CommandRegistrations in each cmd_*.cpp), so adding a
// command never touches main.cpp. A registrar adds its CLI11 subcommand and returns the action
// to run when that subcommand was chosen; the action returns the process exit code.
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace ps::app {

using CommandAction = std::function<int()>;
using CommandRegistrar = std::function<CommandAction(CLI::App& root, CLI::App*& subcommand)>;

std::vector<CommandRegistrar>& registeredCommands();

struct CommandRegistration {
  explicit CommandRegistration(CommandRegistrar r) { registeredCommands().push_back(std::move(r)); }
};

}  // namespace ps::app
