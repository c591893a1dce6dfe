#pragma once
// A well-mixed 64-bit hash of a vertex index (splitmix64's finalizer), for choosing samples
// spread over a file rather than every k-th vertex (which on a regular grid sees a few columns).

#include <cstdint>

namespace meshflow::mesh {

constexpr std::uint64_t index_hash(std::uint64_t x) {
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

}  // namespace meshflow::mesh
