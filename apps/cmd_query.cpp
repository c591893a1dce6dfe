// meshflow query 'SPARQL' [--data DIR] [--format tsv|csv|json|xml|turtle|rdfxml]
#include <iostream>

#include "apps/command.h"
#include "mesh/errors.h"
#include "repository/repository.h"
#include "sparql/protocol.h"

namespace meshflow::apps {
namespace {

struct QueryArgs {
  std::string query, data = "meshflow-data", format = "tsv";
};

int run_query(const QueryArgs& args) {
  using sparql::Format;
  static const std::map<std::string, Format> formats = {
      {"tsv", Format::Tsv},       {"csv", Format::Csv},       {"json", Format::Json},
      {"xml", Format::Xml},       {"turtle", Format::Turtle}, {"rdfxml", Format::RdfXml}};
  Format format = formats.at(args.format);
  if (sparql::is_update(args.query))
    throw InvalidInput("meshflow query answers queries only; SPARQL Update is refused");
  repository::Repository repo(args.data);
  auto graph_format = format == Format::RdfXml ? "rdfxml" : "turtle";
  auto result = repo.store().query(args.query, {}, graph_format);
  if (result.kind == repository::QueryResult::Kind::Graph) {
    std::cout << result.graph;
  } else {
    if (format == Format::Turtle || format == Format::RdfXml) format = Format::Tsv;
    std::cout << sparql::write_results(result, format);
  }
  return 0;
}

void add_query_command(CLI::App& app, int& exit_status) {
  auto args = std::make_shared<QueryArgs>();
  CLI::App* cmd = app.add_subcommand("query", "Run a SPARQL query on the local store");
  cmd->add_option("query", args->query, "The SPARQL query")->required();
  cmd->add_option("--data", args->data, "Data directory");
  cmd->add_option("--format", args->format, "Output format")
      ->check(CLI::IsMember({"tsv", "csv", "json", "xml", "turtle", "rdfxml"}));
  cmd->callback([args, &exit_status] { exit_status = run_query(*args); });
}

}  // namespace

MESHFLOW_COMMAND(query, add_query_command);

}  // namespace meshflow::apps
