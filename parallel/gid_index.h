#pragma once
// Where a global vertex id sits in an ascending list of them, in about constant time: the ids
// are bucketed by value (64 ids a bucket, wider when the list is sparse: never more buckets
// than ids) and each bucket remembers where its ids start. This replaced a binary search over
// the whole list per triangle corner, which was most of a partition's time.

#include <algorithm>
#include <cstdint>
#include <vector>

namespace meshflow::parallel {

class GidIndex {
 public:
  static constexpr std::size_t npos = ~std::size_t{0};

  explicit GidIndex(std::vector<std::uint32_t> ascending) : gids_(std::move(ascending)) {
    if (gids_.empty()) return;
    while ((std::uint64_t{gids_.back() - gids_.front()} >> shift_) > gids_.size()) ++shift_;
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
    auto first = gids_.begin() + start_[b], last = gids_.begin() + start_[b + 1];
    auto it = std::lower_bound(first, last, gid);  // dense runs: at most 64 ids, a cache line or two
    return it != last && *it == gid ? static_cast<std::size_t>(it - gids_.begin()) : npos;
  }

 private:
  std::size_t bucket(std::uint32_t gid) const { return (gid - gids_.front()) >> shift_; }
  unsigned shift_ = 6;
  std::vector<std::uint32_t> gids_;
  std::vector<std::uint32_t> start_;
};

}  // namespace meshflow::parallel
