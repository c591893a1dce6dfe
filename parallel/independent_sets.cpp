#include "parallel/independent_sets.h"

#include <algorithm>
#include <numeric>

#include "mesh/errors.h"

namespace meshflow::parallel {

std::vector<std::vector<std::uint32_t>> independent_sets(const PartGraph& adjacency, std::size_t max_set) {
  if (max_set == 0) throw InvalidInput("independent sets need at least one part each");
  const std::size_t n = adjacency.size();
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return adjacency[a].size() > adjacency[b].size(); });
  constexpr std::uint32_t kNone = ~0u;
  std::vector<std::uint32_t> colour(n, kNone);
  std::vector<std::vector<std::uint32_t>> classes;
  for (std::uint32_t p : order) {
    std::vector<bool> taken(classes.size() + 1, false);
    for (std::uint32_t q : adjacency[p])
      if (colour[q] != kNone) taken[colour[q]] = true;
    std::uint32_t c = 0;
    while (taken[c]) ++c;
    colour[p] = c;
    if (c == classes.size()) classes.emplace_back();
    classes[c].push_back(p);
  }
  std::vector<std::vector<std::uint32_t>> sets;
  for (auto& members : classes) {
    std::sort(members.begin(), members.end());
    for (std::size_t i = 0; i < members.size(); i += max_set)
      sets.emplace_back(members.begin() + i, members.begin() + std::min(members.size(), i + max_set));
  }
  return sets;
}

}  // namespace meshflow::parallel
