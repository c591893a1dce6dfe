#pragma once
// The side index of search (DESIGN §7 allows it for free text): one row per workflow with the
// fields a result list shows, and an FTS5 table over name and description for ranking. Written
// right after the triples of the workflow, removed with them. Filters of meaning (purpose, data
// type, operation, creator, kind) are never answered from here, only from the triples.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "repository/repository.h"

namespace meshflow::repository {

class SearchIndex {
 public:
  explicit SearchIndex(const std::filesystem::path& file);  // \throws IoError
  ~SearchIndex();
  void put(const WorkflowSummary& w);
  void remove(const std::string& id);
  bool empty();
  void clear();  // a store found empty drops what an earlier store left here
  // Ids whose name or description hold every word (as a word prefix), best bm25 first (name
  // weighs 3, description 1).
  std::vector<std::string> match(const std::vector<std::string>& words);
  // One page of match() and how many match in all (text alone: no other filter to intersect).
  std::vector<std::string> match_page(const std::vector<std::string>& words, std::uint64_t offset,
                                      std::uint64_t limit, std::uint64_t& total);
  std::vector<std::string> newest_first();
  std::optional<WorkflowSummary> summary(const std::string& id);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace meshflow::repository
