// meshflow hub [--port P] [--data DIR]  and  meshflow up [--nodes N] [--port P] [--data DIR]
#include <unistd.h>

#include <chrono>
#include <iostream>
#include <thread>

#include "apps/command.h"
#include "apps/signals.h"
#include "mesh/errors.h"
#include "web/hub_server.h"
#include "web/node_supervisor.h"
#include "web/repository_routes.h"
#include "web/ui_routes.h"

namespace meshflow::apps {
namespace {

struct HubArgs {
  std::string host = "127.0.0.1";
  int port = 8080;
  std::string data = "meshflow-data";
  int nodes = 2;
  bool allow_private_fetch = false;
  int max_loop = 100;
  std::string transfer = "smaller";
  std::string store = "redland";
};

web::HubOptions hub_options(const HubArgs& args) {
  web::HubOptions options;
  options.host = args.host;
  options.port = args.port;
  options.data_dir = args.data;
  options.allow_private_fetch = args.allow_private_fetch;
  options.max_loop_iterations = args.max_loop;
  options.default_transfer = args.transfer;
  return options;
}

std::string self_executable() {
  std::error_code error;
  auto path = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) throw IoError("cannot find this executable (/proc/self/exe)");
  return path.string();
}

void announce(const web::HubServer& hub) {
  // DESIGN §1: the first line of standard output, flushed, only once ready.
  std::cout << "meshflow: ready at " << hub.url() << std::endl;
}

// What the hub serves beside jobs: the repository (store, accounts) and the browser UI. The
// store opens and the examples load before the server starts, so ready means loaded.
struct HubRoutes {
  repository::Repository repo;
  repository::Accounts accounts;
  web::Auth auth;
  HubRoutes(web::HubServer& hub, const HubArgs& args)
      : repo(args.data, repository::StoreConfig::parse(args.store)), accounts(args.data, repo), auth(accounts) {
    web::add_account_routes(hub, auth);
    web::add_repository_routes(hub, repo, auth);
    hub.set_service_curator_check([this](const httplib::Request& req) { auth.require(req, "curator"); });
    web::add_ui_routes(hub.http(), web::default_ui_dir());
  }
};

int run_hub(const HubArgs& args) {
  block_stop_signals();
  web::HubServer hub(hub_options(args));
  HubRoutes routes(hub, args);
  hub.start();
  announce(hub);
  wait_for_stop_signal();
  hub.stop();
  return 0;
}

int run_up(const HubArgs& args) {
  if (args.nodes < 0) throw InvalidInput("--nodes must be >= 0");
  block_stop_signals();
  web::HubServer hub(hub_options(args));
  HubRoutes routes(hub, args);
  hub.start();
  std::size_t expected = static_cast<std::size_t>(args.nodes);
  hub.set_ready_condition(
      [&hub, expected] { return hub.registrations_since_start() >= expected; });
  web::NodeSupervisor nodes(self_executable(), hub.url(), hub.token_file(), args.data, args.nodes);
  nodes.start();
  // Nodes registered before a restart are remembered; wait for this start's count.
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!hub.is_ready()) {
    if (std::chrono::steady_clock::now() > deadline) {
      nodes.stop();
      throw IoError("the nodes did not register with the hub within 60 s");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  announce(hub);
  int signal = wait_for_stop_signal();
  std::cerr << "meshflow: stopping (signal " << signal << ")\n";
  nodes.stop();
  hub.stop();
  return 0;
}

void add_common(CLI::App* cmd, HubArgs& args) {
  cmd->add_option("--port", args.port, "Port to listen on (0: any free port)");
  cmd->add_option("--host", args.host, "Address to listen on");
  cmd->add_option("--data", args.data, "Data directory");
  cmd->add_option("--store", args.store,
                  "RDF store: 'redland' (sqlite under --data) or "
                  "'virtuoso=URL[,graph=URI][,user=U][,password=P]' (a Virtuoso SPARQL endpoint)");
  cmd->add_flag("--allow-private-fetch", args.allow_private_fetch,
                "Let jobs fetch input_url from loopback and private addresses");
  cmd->add_option("--max-loop", args.max_loop, "Bound on the iterations of each while loop of a job")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--transfer", args.transfer,
                  "What later nodes receive after each step, for jobs that do not say: 'smaller' (the "
                  "correction or the output, whichever is smaller) or 'output' (always the whole mesh)")
      ->check(CLI::IsMember({"smaller", "output"}));
}

void add_hub_commands(CLI::App& app, int& exit_status) {
  auto hub_args = std::make_shared<HubArgs>();
  CLI::App* hub = app.add_subcommand("hub", "Run the hub: repository, SPARQL endpoint, engine, web UI");
  add_common(hub, *hub_args);
  hub->callback([hub_args, &exit_status] { exit_status = run_hub(*hub_args); });

  auto up_args = std::make_shared<HubArgs>();
  CLI::App* up = app.add_subcommand("up", "Run the hub with local nodes as child processes");
  add_common(up, *up_args);
  up->add_option("--nodes", up_args->nodes, "Number of local nodes");
  up->callback([up_args, &exit_status] { exit_status = run_up(*up_args); });
}

}  // namespace

MESHFLOW_COMMAND(hub, add_hub_commands);

}  // namespace meshflow::apps
