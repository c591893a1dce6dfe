#pragma once
// The Virtuoso backend: OpenLink Virtuoso (a separate server with full SPARQL 1.1) reached
// over HTTP with libcurl. Queries: POST to the SPARQL endpoint with the repository's graph as
// the default graph; results as SPARQL JSON (Virtuoso writes the SPARQL 1.0 "typed-literal").
// Writes: SPARQL Update (INSERT DATA, DELETE ... WHERE) to the endpoint's -auth twin with
// digest authentication. Safe to call from many threads (one HTTP connection per call).

#include <memory>
#include <string>

#include "repository/rdf_store.h"

namespace meshflow::repository {

class VirtuosoStore final : public RdfStore {
 public:
  // Checks that the endpoint answers. \throws IoError.
  explicit VirtuosoStore(const StoreConfig& config);
  ~VirtuosoStore() override;

  std::string backend() const override { return "virtuoso"; }
  bool created_now() const override;
  QueryResult query(const std::string& sparql, const QueryLimits& limits = {},
                    const std::string& graph_format = "turtle") override;
  std::vector<std::string> subjects(const std::string& predicate,
                                    const std::string& object) override;
  void load_rdfxml(const std::string& text, const std::string& base_uri) override;
  void add(const std::vector<Triple>& triples) override;
  void remove_subject(const std::string& subject) override;
  std::uint64_t size() override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// SPARQL 1.1 Query Results JSON (and SPARQL 1.0's "typed-literal") into a QueryResult.
// \throws ParseError naming the byte or the part that is wrong, LimitExceeded (rows).
QueryResult parse_sparql_json(const std::string& body, std::uint64_t max_rows);

// The form of a query by its first keyword after the prologue: "select", "ask", "construct",
// "describe", or "" when none of these.
std::string query_form(const std::string& sparql);

}  // namespace meshflow::repository
