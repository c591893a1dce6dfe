#include "parallel/cell_ids.h"

#include <unistd.h>

#include <algorithm>
#include <cstring>

#include "mesh/errors.h"

namespace meshflow::parallel {

CellIds::CellIds(std::string path, std::size_t max_windows)
    : path_(std::move(path)), max_windows_(std::max<std::size_t>(max_windows, 1)) {
  file_ = std::fopen(path_.c_str(), "w+b");
  if (!file_) throw IoError(path_ + ": cannot create the cell-id file: " + std::strerror(errno));
  tail_.reserve(kWindow);
}

CellIds::~CellIds() {
  std::fclose(file_);
  std::remove(path_.c_str());
}

void CellIds::push_back(std::uint32_t cell) {
  tail_.push_back(cell);
  if (tail_.size() < kWindow) return;
  if (std::fwrite(tail_.data(), sizeof(std::uint32_t), tail_.size(), file_) != tail_.size() || std::fflush(file_) != 0)
    throw IoError(path_ + ": cannot write the cell-id file (disk full?)");
  tail_.clear();
  ++written_;
}

const std::vector<std::uint32_t>& CellIds::load(std::uint64_t w) {
  ++clock_;
  for (std::size_t i = 0; i < cache_.size(); ++i)
    if (cache_[i].index == w) {
      cache_[i].used = clock_;
      last_ = i;
      return cache_[i].ids;
    }
  if (cache_.size() < max_windows_) {
    cache_.emplace_back();
    last_ = cache_.size() - 1;
  } else {
    last_ = static_cast<std::size_t>(
        std::min_element(cache_.begin(), cache_.end(), [](const Window& a, const Window& b) { return a.used < b.used; }) -
        cache_.begin());
  }
  Window& slot = cache_[last_];
  slot.index = w;
  slot.used = clock_;
  slot.ids.resize(kWindow);
  const std::size_t bytes = kWindow * sizeof(std::uint32_t);
  std::size_t done = 0;
  while (done < bytes) {
    ssize_t n = ::pread(fileno(file_), reinterpret_cast<char*>(slot.ids.data()) + done, bytes - done,
                        static_cast<off_t>(w * bytes + done));
    if (n <= 0) {
      slot.index = ~std::uint64_t{0};
      throw IoError(path_ + ": cannot read the cell-id file back at byte " + std::to_string(w * bytes + done));
    }
    done += static_cast<std::size_t>(n);
  }
  ++loads_;
  return slot.ids;
}

}  // namespace meshflow::parallel
