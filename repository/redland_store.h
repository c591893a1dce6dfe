#pragma once
// The default backend: one Redland world, storage and model, owned by one worker thread that
// runs every request from a queue (rasqal and the sqlite storage are not safe to share between
// threads). SQLite storage under a folder, with the literal index of GROUND.md §1. Queries are
// stopped at their deadline from inside rasqal: the storage is sqlite wrapped so that every
// triple stream it hands rasqal ends once the deadline has passed. subjects() reads the
// storage's tables with SQL (one pattern needs no rasqal).

#include <filesystem>
#include <memory>

#include "repository/rdf_store.h"

namespace meshflow::repository {

class RedlandStore final : public RdfStore {
 public:
  // Opens (creating when absent) the sqlite store DIR/store.db. \throws IoError.
  explicit RedlandStore(const std::filesystem::path& dir);
  ~RedlandStore() override;
  RedlandStore(const RedlandStore&) = delete;
  RedlandStore& operator=(const RedlandStore&) = delete;

  std::string backend() const override { return "redland"; }
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

}  // namespace meshflow::repository
