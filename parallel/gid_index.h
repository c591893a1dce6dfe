#pragma once
// Where a global vertex id sits in an ascending list of them, in about constant time: the ids
// are bucketed by value (64 ids a bucket) and each bucket remembers where its ids start. The
// table is 4 bytes per 64 ids of the list's range (16 MB for a part spread over 250M ids),
// replacing a binary search per triangle corner, which was most of a partition's time.

#include <cstdint>
#include <vector>

namespace meshflow::parallel {

class GidIndex {
 public:
  static constexpr std::size_t npos = ~std::size_t{0};

  explicit GidIndex(std::vector<std::uint32_t> ascending) : gids_(std::move(ascending)) {
    if (gids_.empty()) return;
    const std::size_t buckets = bucket(gids_.back()) + 2;
    start_.resize(buckets);
    std::size_t i = 0;
    for (std::size_t b = 0; b < buckets; ++b) {
      while (i < gids_.size() && bucket(gids_[i]) < b) ++i;
      start_[b] = static_cast<std::uint32_t>(i);
    }
  }
  // The position of gid in the list, or npos.
  std::size_t find(std::uint32_t gid) const {
    if (gids_.empty() || gid < gids_.front() || gid > gids_.back()) return npos;
    const std::size_t b = bucket(gid);
    for (std::size_t i = start_[b]; i < start_[b + 1]; ++i)
      if (gids_[i] == gid) return i;
    return npos;
  }

 private:
  std::size_t bucket(std::uint32_t gid) const { return (gid - gids_.front()) >> 6; }
  std::vector<std::uint32_t> gids_;
  std::vector<std::uint32_t> start_;
};

}  // namespace meshflow::parallel
