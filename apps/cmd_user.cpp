// meshflow user add NAME --role user|curator|admin [--password-file F] [--data DIR]
// (without --password-file the password is the first line of standard input)
#include <fstream>
#include <iostream>

#include "apps/command.h"
#include "mesh/errors.h"
#include "repository/accounts.h"

namespace meshflow::apps {
namespace {

struct UserArgs {
  std::string name, role = "user", password_file, data = "meshflow-data";
};

int run_user_add(const UserArgs& args) {
  std::string password;
  if (!args.password_file.empty()) {
    std::ifstream in(args.password_file);
    if (!in) throw IoError("cannot read " + args.password_file);
    std::getline(in, password);
  } else {
    std::getline(std::cin, password);
  }
  if (!password.empty() && password.back() == '\r') password.pop_back();
  repository::Repository repo(args.data);
  repository::Accounts accounts(args.data, repo);
  auto account = accounts.add(args.name, password, args.role);
  std::cout << "added " << account.name << " (" << account.role << ")\n";
  return 0;
}

void add_user_command(CLI::App& app, int& exit_status) {
  auto args = std::make_shared<UserArgs>();
  CLI::App* user = app.add_subcommand("user", "Manage accounts");
  user->require_subcommand(1);
  CLI::App* add = user->add_subcommand("add", "Add an account");
  add->add_option("name", args->name, "User name")->required();
  add->add_option("--role", args->role, "Role")->check(CLI::IsMember({"user", "curator", "admin"}));
  add->add_option("--password-file", args->password_file, "File whose first line is the password");
  add->add_option("--data", args->data, "Data directory");
  add->callback([args, &exit_status] { exit_status = run_user_add(*args); });
}

}  // namespace

MESHFLOW_COMMAND(user, add_user_command);

}  // namespace meshflow::apps
