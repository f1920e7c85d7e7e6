// planetsculpt: the command-line entry point. Each subcommand lives in its own cmd_*.cpp and
// registers itself (app/command_registry.hpp).
#include <iostream>

#include "app/command_registry.hpp"
#include "app/openmp_wait.hpp"
#include "core/input_error.hpp"

namespace ps::app {
std::vector<CommandRegistrar>& registeredCommands() {
  static std::vector<CommandRegistrar> all;
  return all;
}
}  // namespace ps::app

int main(int argc, char** argv) {
  ps::app::settleOpenMpWaiting(argc, argv);
  CLI::App cli{"PlanetSculpt: sculpt spherical planets in augmented reality"};
  cli.require_subcommand(1);
  std::vector<std::pair<CLI::App*, ps::app::CommandAction>> commands;
  for (const auto& registrar : ps::app::registeredCommands()) {
    CLI::App* sub = nullptr;
    auto action = registrar(cli, sub);
    commands.emplace_back(sub, std::move(action));
  }
  CLI11_PARSE(cli, argc, argv);
  try {
    for (auto& [sub, action] : commands) {
      if (sub && sub->parsed()) return action();
    }
  } catch (const ps::core::InputError& e) {
    std::cerr << "planetsculpt: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "planetsculpt: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
