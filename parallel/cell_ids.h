#pragma once
// The cell of every input vertex during the partition's pass 2 (DESIGN §9: "the per-vertex
// cell-id file, loaded in windows when it does not fit"): 4 bytes per vertex appended to a
// scratch file in windows of 1M ids, read back for the triangles through an LRU of loaded windows
// (64 by default: at most 256 MB, whatever the input's size). Ids not yet in a whole window stay
// in memory, so formats that interleave vertices and faces (OBJ) work too.

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace meshflow::parallel {

class CellIds {
 public:
  static constexpr std::uint64_t kWindow = 1u << 20;

  // Creates (truncates) the scratch file at `path`; the destructor removes it.
  explicit CellIds(std::string path, std::size_t max_windows = 64);
  ~CellIds();
  CellIds(const CellIds&) = delete;
  CellIds& operator=(const CellIds&) = delete;

  void push_back(std::uint32_t cell);
  std::uint64_t size() const { return written_ * kWindow + tail_.size(); }
  // The cell of vertex v < size(). \throws IoError when the file cannot be read back.
  std::uint32_t operator[](std::uint64_t v) {
    const std::uint64_t w = v / kWindow;
    if (w == written_) return tail_[v % kWindow];
    if (last_ < cache_.size() && cache_[last_].index == w) return cache_[last_].ids[v % kWindow];
    return load(w)[v % kWindow];
  }
  std::uint64_t windows_loaded() const { return loads_; }

 private:
  struct Window {
    std::uint64_t index = 0, used = 0;
    std::vector<std::uint32_t> ids;
  };
  const std::vector<std::uint32_t>& load(std::uint64_t w);

  std::string path_;
  std::FILE* file_ = nullptr;
  std::size_t max_windows_;
  std::vector<std::uint32_t> tail_;
  std::uint64_t written_ = 0;  // whole windows in the file
  std::vector<Window> cache_;
  std::size_t last_ = 0;  // the slot of the last window used
  std::uint64_t clock_ = 0, loads_ = 0;
};

}  // namespace meshflow::parallel
