#pragma once
// Greedy colouring of the part adjacency graph (parts sharing a vertex are adjacent), most
// connected part first, each part taking the lowest colour none of its neighbours has; each
// colour class is then cut into sets of at most `max_set` parts (DESIGN §9: N = nodes). No
// two parts of a set are adjacent.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace meshflow::parallel {

using PartGraph = std::vector<std::vector<std::uint32_t>>;  // neighbours of each part

std::vector<std::vector<std::uint32_t>> independent_sets(const PartGraph& adjacency, std::size_t max_set);

}  // namespace meshflow::parallel
