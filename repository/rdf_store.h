#pragma once
// The RDF store behind the repository (DESIGN §7): one interface, two backends.
// - Redland with the SQLite storage under the data folder (the default; redland_store.h).
// - OpenLink Virtuoso reached over its SPARQL HTTP endpoint (virtuoso_store.h).
// The repository's own queries use only what both answer the same way.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
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
  virtual ~RdfStore() = default;

  virtual std::string backend() const = 0;  // "redland" or "virtuoso"
  virtual bool created_now() const = 0;     // true when this open found the store empty

  // SPARQL query. Graph results are serialized as `graph_format` ("turtle" or "rdfxml").
  // \throws ParseError (syntax or a feature the backend lacks), LimitExceeded (rows),
  // QueryTimeout, IoError (the backend cannot be reached).
  virtual QueryResult query(const std::string& sparql, const QueryLimits& limits = {},
                            const std::string& graph_format = "turtle") = 0;
  // The subjects of the triples (?s predicate object), object a URI: one triple pattern, the
  // search's filters of meaning. Redland answers it from the storage without rasqal.
  virtual std::vector<std::string> subjects(const std::string& predicate,
                                            const std::string& object) = 0;
  // Parses an RDF/XML document into the store. \throws ParseError.
  virtual void load_rdfxml(const std::string& text, const std::string& base_uri) = 0;
  // Adds triples in one transaction (Redland) or one update request per batch (Virtuoso).
  virtual void add(const std::vector<Triple>& triples) = 0;
  // Removes every triple whose subject is `subject`.
  virtual void remove_subject(const std::string& subject) = 0;
  virtual std::uint64_t size() = 0;
};

// Which backend: `redland` (the default) or `virtuoso=URL[,graph=URI][,user=U][,password=P]`
// with URL the SPARQL endpoint (writes go to URL-auth, e.g. /sparql-auth, with digest auth).
struct StoreConfig {
  std::string virtuoso;  // the endpoint; empty: Redland + sqlite
  std::string graph = "http://meshflow.org/graph/repository";
  std::string user = "dba";
  std::string password = "dba";
  static StoreConfig parse(const std::string& spec);  // \throws InvalidInput
};

// Opens the store: Redland under `dir` (store.db), or the Virtuoso graph. \throws IoError.
std::unique_ptr<RdfStore> open_store(const StoreConfig& config, const std::filesystem::path& dir);

// The first keyword of a SPARQL request after its prologue (comments, PREFIX and BASE
// declarations), lower-cased: "select", "insert", ...; "" when there is none.
std::string sparql_first_keyword(const std::string& text);

// A query ran past its time bound.
class QueryTimeout : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace meshflow::repository
