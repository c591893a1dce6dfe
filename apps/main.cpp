// meshflow: one executable, subcommands (DESIGN §1). Exit status: 0 done, 1 failed,
// 2 bad input or usage.
#include <algorithm>
#include <cstdio>
#include <exception>
#include <iostream>

#include "apps/command.h"
#include "mesh/errors.h"

namespace meshflow::apps {

CommandRegistration::CommandRegistration(std::string name, CommandFactory factory) {
  command_registry().emplace_back(std::move(name), std::move(factory));
}

std::vector<std::pair<std::string, CommandFactory>>& command_registry() {
  static std::vector<std::pair<std::string, CommandFactory>> registry;
  return registry;
}

}  // namespace meshflow::apps

int main(int argc, char** argv) {
  using namespace meshflow;
  CLI::App app{"meshflow: an executable workflow repository for large triangle meshes"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "meshflow 0.1.0");
  int exit_status = 0;
  auto& registry = apps::command_registry();
  std::sort(registry.begin(), registry.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  for (auto& [name, factory] : registry) factory(app, exit_status);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  } catch (const InvalidInput& e) {  // ParseError included
    std::cerr << "meshflow: " << e.what() << "\n";
    return 2;
  } catch (const LimitExceeded& e) {
    std::cerr << "meshflow: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "meshflow: " << e.what() << "\n";
    return 1;
  }
  std::cout.flush();
  return exit_status;
}
