#pragma once
// The workflow repository (DESIGN §7): workflows (XML file + RDF instance), static
// documentation workflows, the purpose taxonomy and data types of the Workflow Ontology, and
// semantic search over them. Opens DATA/repository/ and, on first start, loads the ontology
// and the thesis's example workflows.

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "mesh/errors.h"
#include "repository/rdf_store.h"

namespace meshflow::repository {

inline constexpr const char* kWo = "http://meshflow.org/ontology/wo#";
inline constexpr const char* kWorkflowBase = "http://meshflow.org/workflow/";
inline constexpr const char* kUserBase = "http://meshflow.org/user/";

struct WorkflowSummary {
  std::string id, name, description, creator, created;  // created: xsd:dateTime text
  std::vector<std::string> domains;                      // as filed (most specific)
  std::string type;                                      // "executable" or "static"
};

struct WorkflowDetail : WorkflowSummary {
  std::vector<std::string> operations, inputs, outputs;
};

struct NewWorkflow {
  std::string name, description, creator;
  std::vector<std::string> domains;
  std::string type = "executable";
  std::string xml;                      // required for executables
  std::vector<std::string> operations;  // static workflows: what they use
  std::string id;                       // empty: a fresh one
};

struct SearchQuery {
  std::string q, domain, input, output, operation, creator, type;
  // Set: executable workflows only, every operation of which is in this set (runnable now).
  std::optional<std::vector<std::string>> runnable_with;
  std::uint64_t offset = 0, limit = 20;
};

// A workflow step failed validation: the step's operation name beside line and column.
class StepError : public ParseError {
 public:
  StepError(const ParseError& cause, std::string operation)
      : ParseError(cause.where(), cause.reason()), operation_(std::move(operation)) {}
  const std::string& operation() const { return operation_; }

 private:
  std::string operation_;
};

struct SearchPage {
  std::vector<WorkflowSummary> workflows;
  std::uint64_t total = 0, offset = 0, limit = 0;
};

struct Purpose {
  std::string name, label;
  std::optional<std::string> parent;
};

// The Workflow Ontology (ontology/wo.owl, compiled in).
const char* ontology_rdfxml();

class Repository {
 public:
  // Opens the store `store` says (Redland + sqlite under DATA/repository by default).
  // \throws IoError, ParseError (a broken ontology or example).
  explicit Repository(const std::filesystem::path& data_dir, const StoreConfig& store = {});
  ~Repository();

  RdfStore& store();
  // Validates (XSD + operations; names and purposes) and stores. Returns the id.
  // \throws StepError (a step: line, column, operation), ParseError (XML: line and column),
  // InvalidInput.
  std::string create(const NewWorkflow& workflow);
  std::optional<WorkflowDetail> get(const std::string& id);
  std::optional<std::string> xml(const std::string& id);
  bool remove(const std::string& id);  // triples and file; false when unknown
  SearchPage search(const SearchQuery& query);  // \throws InvalidInput
  std::vector<Purpose> purposes() const;
  std::vector<std::string> datatypes() const;
  std::size_t example_count() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace meshflow::repository
