// meshflow node --hub URL --token-file F [--listen ADDR:PORT] [--advertise URL] [--data DIR]
#include <fstream>
#include <iostream>

#include "apps/command.h"
#include "apps/signals.h"
#include "mesh/errors.h"
#include "services/node_server.h"
#include "services/operation.h"

namespace meshflow::apps {
namespace {

struct NodeArgs {
  std::string hub;
  std::string token_file;
  std::string listen = "127.0.0.1:0";
  std::string advertise;
  std::string data = "meshflow-node-data";
  std::uint64_t capacity = 50'000'000;
  std::vector<std::string> offer;
  int answer_within_ms = 20'000;
};

std::string read_token(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InvalidInput("cannot read the token file " + path);
  std::string token;
  std::getline(in, token);
  while (!token.empty() && (token.back() == '\r' || token.back() == ' ')) token.pop_back();
  if (token.empty()) throw InvalidInput("the token file " + path + " is empty");
  return token;
}

int run_node(const NodeArgs& args) {
  services::NodeOptions options;
  auto colon = args.listen.rfind(':');
  if (colon == std::string::npos) throw InvalidInput("--listen wants ADDR:PORT, got " + args.listen);
  options.host = args.listen.substr(0, colon);
  try {
    options.port = std::stoi(args.listen.substr(colon + 1));
  } catch (const std::exception&) {
    throw InvalidInput("--listen wants ADDR:PORT, got " + args.listen);
  }
  options.advertise_url = args.advertise;
  options.data_dir = args.data;
  options.hub_url = args.hub;
  options.capacity_vertices = args.capacity;
  for (const auto& name : args.offer) services::find_operation(name);  // unknown: exit 2
  options.operations = args.offer;
  if (args.answer_within_ms < 0) throw InvalidInput("--answer-within-ms must be >= 0");
  options.answer_within = std::chrono::milliseconds(args.answer_within_ms);
  if (!args.token_file.empty()) options.token = read_token(args.token_file);
  if (!args.hub.empty() && options.token.empty())
    throw InvalidInput("--hub needs --token-file (the hub's DATA/node.token)");

  block_stop_signals();
  services::NodeServer node(options);
  node.start();
  node.register_with_hub();
  std::cout << "meshflow: node ready at " << node.url() << std::endl;
  wait_for_stop_signal();
  node.stop();
  return 0;
}

void add_node_command(CLI::App& app, int& exit_status) {
  auto args = std::make_shared<NodeArgs>();
  CLI::App* cmd = app.add_subcommand("node", "Serve mesh operations over HTTP (a node of the hub)");
  cmd->add_option("--hub", args->hub, "The hub's URL to register with");
  cmd->add_option("--token-file", args->token_file, "File holding the hub's node token");
  cmd->add_option("--listen", args->listen, "Address and port to listen on (port 0: any free)");
  cmd->add_option("--advertise", args->advertise, "URL others reach this node at");
  cmd->add_option("--data", args->data, "Data directory (cache and files)");
  cmd->add_option("--capacity", args->capacity, "Largest mesh taken in memory, in vertices");
  cmd->add_option("--offer", args->offer, "Offer only these operations (comma-separated; default: all)")
      ->delimiter(',');
  cmd->add_option("--answer-within-ms", args->answer_within_ms,
                  "A /run still running after this answers 202 with a task URL to poll");
  cmd->callback([args, &exit_status] { exit_status = run_node(*args); });
}

}  // namespace

MESHFLOW_COMMAND(node, add_node_command);

}  // namespace meshflow::apps
