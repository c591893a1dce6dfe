#pragma once
// The RDF store: one Redland world, storage and model, owned by one worker thread that runs
// every request from a queue (rasqal and the sqlite storage are not safe to share between
// threads). SQLite storage under a folder, with the literal index of GROUND.md §1.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <future>
#include <memory>
#include <string>
#include <vector>

namespace meshflow::repository {

// One RDF term as a query answers it.
struct Term {
  enum class Kind { Unbound, Uri, Literal, Blank };
  Kind kind = Kind::Unbound;
  std::string value;
  std::string datatype;  // literals only, empty when plain
  std::string language;  // literals only
};

// A triple to add or remove: object is a URI unless `literal` (with optional datatype).
struct Triple {
  std::string subject;
  std::string predicate;
  std::string object;
  bool literal = false;
  std::string datatype;
};

struct QueryLimits {
  std::uint64_t max_rows = 100000;
  std::chrono::milliseconds timeout{10000};
};

struct QueryResult {
  enum class Kind { Bindings, Boolean, Graph };
  Kind kind = Kind::Bindings;
  std::vector<std::string> variables;
  std::vector<std::vector<Term>> rows;
  bool boolean = false;
  std::string graph;  // serialized in the format asked for (graph results only)
};

class RdfStore {
 public:
  // Opens (creating when absent) the sqlite store DIR/store.db. \throws IoError.
  explicit RdfStore(const std::filesystem::path& dir);
  ~RdfStore();
  RdfStore(const RdfStore&) = delete;
  RdfStore& operator=(const RdfStore&) = delete;

  bool created_now() const;  // true when this open created the store

  // SPARQL query. Graph results are serialized as `graph_format` ("turtle" or "rdfxml").
  // \throws ParseError (syntax or a feature rasqal lacks), LimitExceeded (rows), QueryTimeout.
  QueryResult query(const std::string& sparql, const QueryLimits& limits = {},
                    const std::string& graph_format = "turtle");
  // Parses an RDF/XML document into the store (one transaction). \throws ParseError.
  void load_rdfxml(const std::string& text, const std::string& base_uri);
  // Adds / removes triples in one transaction.
  void add(const std::vector<Triple>& triples);
  // Removes every triple whose subject is `subject`.
  void remove_subject(const std::string& subject);
  std::uint64_t size();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A query ran past its time bound.
class QueryTimeout : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace meshflow::repository
