#include "web/repository_routes.h"

#include <httplib.h>

#include <nlohmann/json.hpp>

#include "mesh/errors.h"
#include "protocol/http_server.h"
#include "sparql/protocol.h"

namespace meshflow::web {
namespace {

using nlohmann::json;

json summary_json(const repository::WorkflowSummary& w) {
  return {{"id", w.id},           {"name", w.name},       {"description", w.description},
          {"creator", w.creator}, {"created", w.created}, {"domains", w.domains},
          {"type", w.type}};
}

std::uint64_t number_param(const httplib::Request& req, const char* name, std::uint64_t fallback,
                           std::uint64_t max) {
  if (!req.has_param(name)) return fallback;
  const std::string v = req.get_param_value(name);
  if (v.empty() || v.size() > 9 || v.find_first_not_of("0123456789") != std::string::npos)
    throw InvalidInput(std::string(name) + " must be a whole number, not \"" + v + "\"");
  auto n = std::stoull(v);
  if (n > max) throw InvalidInput(std::string(name) + " must be at most " + std::to_string(max));
  return n;
}

void check_body(const httplib::Request& req, std::size_t max) {
  if (req.body.size() > max)
    throw LimitExceeded("request body bytes", max, req.body.size());
}

// SPARQL 1.1 Protocol: the query from GET ?query=, a POST form, or a POST sparql-query body.
void answer_sparql(repository::RdfStore& store, const SparqlLimits& limits,
                   const httplib::Request& req, httplib::Response& res) {
  check_body(req, limits.max_body);
  std::string type = req.get_header_value("Content-Type");
  std::string query;
  if (req.method == "POST" && type.rfind("application/sparql-update", 0) == 0)
    throw protocol::Forbidden("this endpoint answers queries only; SPARQL Update is refused");
  if (req.has_param("update"))
    throw protocol::Forbidden("this endpoint answers queries only; SPARQL Update is refused");
  if (req.method == "POST" && type.rfind("application/sparql-query", 0) == 0) query = req.body;
  else if (req.has_param("query")) query = req.get_param_value("query");
  else throw InvalidInput("no query: send ?query=, a form field 'query' or an application/sparql-query body");
  if (sparql::is_update(query))
    throw protocol::Forbidden("this endpoint answers queries only; SPARQL Update is refused");
  std::string accept = req.get_header_value("Accept");
  // Which kind of result is not known before the query runs; choose both ways now.
  auto table_format = sparql::choose_format(accept, false);
  auto graph_format = sparql::choose_format(accept, true);
  repository::QueryResult result;
  try {
    result = store.query(query, {limits.max_rows, limits.timeout},
                         sparql::redland_graph_format(graph_format.value_or(sparql::Format::Turtle)));
  } catch (const repository::QueryTimeout& e) {
    protocol::reply_error(res, 503, e.what());
    return;
  }
  bool graph = result.kind == repository::QueryResult::Kind::Graph;
  auto format = graph ? graph_format : table_format;
  if (!format) {
    protocol::reply_error(res, 406, "none of the types in Accept can carry this result (\"" +
                                        accept + "\")");
    return;
  }
  res.set_header("Vary", "Accept");
  if (graph) res.set_content(result.graph, sparql::content_type(*format));
  else res.set_content(sparql::write_results(result, *format), sparql::content_type(*format));
}

}  // namespace

void add_repository_routes(HubServer& hub, repository::Repository& repo, Auth& auth,
                           SparqlLimits limits) {
  auto& server = hub.http();
  server.Post("/api/workflows", [&repo, &auth, limits](const httplib::Request& req,
                                                       httplib::Response& res) {
    check_body(req, limits.max_body);
    auto who = auth.require(req, "user");
    json j;
    try {
      j = json::parse(req.body);
    } catch (const json::exception& e) {  // syntax, or a number out of range
      throw InvalidInput(std::string("the body is not JSON: ") + e.what());
    }
    if (!j.is_object()) throw InvalidInput("the body must be a JSON object");
    auto str = [&](const char* k) {
      if (!j.contains(k)) return std::string();
      if (!j[k].is_string()) throw InvalidInput(std::string("\"") + k + "\" must be a string");
      return j[k].get<std::string>();
    };
    auto list = [&](const char* k) {
      std::vector<std::string> out;
      if (!j.contains(k)) return out;
      if (!j[k].is_array()) throw InvalidInput(std::string("\"") + k + "\" must be a list of names");
      for (auto& v : j[k]) {
        if (!v.is_string()) throw InvalidInput(std::string("\"") + k + "\" must be a list of names");
        out.push_back(v.get<std::string>());
      }
      return out;
    };
    repository::NewWorkflow w;
    w.name = str("name");
    w.description = str("description");
    w.domains = list("domains");
    w.xml = str("xml");
    w.operations = list("operations");
    w.type = j.contains("type") ? str("type") : "executable";
    w.creator = who.name;
    if (w.type == "static" && repository::role_rank(who.role) < repository::role_rank("curator"))
      throw protocol::Forbidden("static (documentation) workflows are filed by curators");
    std::string id;
    try {
      id = repo.create(w);
    } catch (const repository::StepError& e) {
      // The step's operation beside line and column, so that the builder marks the step.
      json where = {{"file", e.where().file}, {"operation", e.operation()}};
      if (e.where().line) where["line"] = *e.where().line;
      if (e.where().column) where["column"] = *e.where().column;
      res.status = 400;
      res.set_content(json{{"error", e.what()}, {"operation", e.operation()}, {"where", where}}.dump(),
                      "application/json");
      return;
    }
    auto d = repo.get(id);
    json out = summary_json(*d);
    out["operations"] = d->operations;
    out["inputs"] = d->inputs;
    out["outputs"] = d->outputs;
    res.status = 201;
    res.set_content(out.dump(), "application/json");
  });
  server.Delete(R"(/api/workflows/([A-Za-z0-9_.-]+))",
                [&repo, &auth](const httplib::Request& req, httplib::Response& res) {
                  auto who = auth.require(req, "user");
                  auto w = repo.get(req.matches[1]);
                  if (!w) throw protocol::NotFound("no workflow " + std::string(req.matches[1]));
                  if (w->creator != who.name &&
                      repository::role_rank(who.role) < repository::role_rank("curator"))
                    throw protocol::Forbidden("only its creator or a curator deletes a workflow");
                  repo.remove(w->id);
                  res.status = 204;
                });
  server.Get("/api/workflows", [&repo, &hub](const httplib::Request& req, httplib::Response& res) {
    repository::SearchQuery q;
    auto text = [&](const char* name) {
      return req.has_param(name) ? req.get_param_value(name) : std::string();
    };
    q.q = text("q");
    q.domain = text("domain");
    q.input = text("input");
    q.output = text("output");
    q.operation = text("operation");
    q.creator = text("creator");
    q.type = text("type");
    std::string runnable = text("runnable");
    if (runnable == "true" || runnable == "1") q.runnable_with = hub.offered_operations();
    else if (!runnable.empty() && runnable != "false" && runnable != "0")
      throw InvalidInput("runnable must be true or false, not \"" + runnable + "\"");
    q.offset = number_param(req, "offset", 0, 100000000);
    q.limit = number_param(req, "limit", 20, 200);
    if (q.q.size() > 1000) throw InvalidInput("q is longer than 1000 characters");
    auto page = repo.search(q);
    json list = json::array();
    for (const auto& w : page.workflows) list.push_back(summary_json(w));
    res.set_content(json{{"workflows", list},
                         {"total", page.total},
                         {"offset", page.offset},
                         {"limit", page.limit}}
                        .dump(),
                    "application/json");
  });
  server.Get(R"(/api/workflows/([A-Za-z0-9_.-]+))",
             [&repo](const httplib::Request& req, httplib::Response& res) {
               auto w = repo.get(req.matches[1]);
               if (!w) throw protocol::NotFound("no workflow " + std::string(req.matches[1]));
               json j = summary_json(*w);
               j["operations"] = w->operations;
               j["inputs"] = w->inputs;
               j["outputs"] = w->outputs;
               res.set_content(j.dump(), "application/json");
             });
  server.Get(R"(/api/workflows/([A-Za-z0-9_.-]+)/xml)",
             [&repo](const httplib::Request& req, httplib::Response& res) {
               auto xml = repo.xml(req.matches[1]);
               if (!xml) throw protocol::NotFound("no workflow XML for " + std::string(req.matches[1]));
               res.set_content(*xml, "application/xml");
             });
  server.Get("/api/domains", [&repo](const httplib::Request&, httplib::Response& res) {
    json list = json::array();
    for (const auto& p : repo.purposes())
      list.push_back({{"name", p.name}, {"label", p.label},
                      {"parent", p.parent ? json(*p.parent) : json(nullptr)}});
    res.set_content(json{{"domains", list}}.dump(), "application/json");
  });
  server.Get("/api/datatypes", [&repo](const httplib::Request&, httplib::Response& res) {
    res.set_content(json{{"datatypes", repo.datatypes()}}.dump(), "application/json");
  });
  server.Get("/ontology/wo", [](const httplib::Request&, httplib::Response& res) {
    res.set_content(repository::ontology_rdfxml(), "application/rdf+xml");
  });
  auto sparql = [&repo, limits](const httplib::Request& req, httplib::Response& res) {
    answer_sparql(repo.store(), limits, req, res);
  };
  server.Get("/sparql", sparql);
  server.Post("/sparql", sparql);
  hub.set_workflow_resolver([&repo](const std::string& id) { return repo.xml(id); });
}

}  // namespace meshflow::web
