#pragma once
// The tagged corpus: the rows of ../shared/data/meshes/MANIFEST.md (counts by an independent
// script), and which of its files a reader must accept or refuse.
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/meshes.h"

namespace meshflow::testing {

struct ManifestRow {
  std::string file;                  // relative to shared_meshes(), e.g. "real/kitten.off"
  std::string v, f, cc, loops, notes;  // "-" where the reference could not parse the file
};

inline std::vector<ManifestRow> manifest() {
  std::ifstream in(shared_meshes() + "/MANIFEST.md");
  std::vector<ManifestRow> rows;
  std::string line;
  auto trim = [](std::string s) {
    s.erase(0, s.find_first_not_of(' '));
    s.erase(s.find_last_not_of(' ') + 1);
    return s;
  };
  while (std::getline(in, line)) {
    if (line.rfind("| ", 0) != 0) continue;
    std::vector<std::string> cells;
    std::stringstream ss(line.substr(1));
    std::string cell;
    while (std::getline(ss, cell, '|')) cells.push_back(trim(cell));
    if (cells.size() < 7 || cells[0] == "file" || cells[0].find('/') == std::string::npos) continue;
    rows.push_back({cells[0], cells[2], cells[3], cells[4], cells[5], cells[6]});
  }
  return rows;
}

// The broken files a reader must refuse (some carry counts in the manifest: index 0 in OBJ,
// out-of-range indices, NaN, trailing faces are refused all the same).
inline bool must_refuse(const std::string& file) {
  static const char* suffixes[] = {"_truncated.ply", "_truncated_ascii.ply", "_count_too_big.ply",
                                   "_count_too_small.off", "_badidx.ply", "_badidx.obj", "_nan.ply",
                                   "_nan.obj", "_stl_badcount.stl", "/empty.off", "/empty.ply",
                                   "/OutOfMemory.off", "/malformed.obj", "/number_formats.obj",
                                   "/issue623.ply"};
  for (const char* s : suffixes)
    if (file.size() >= std::strlen(s) && file.compare(file.size() - std::strlen(s), std::string::npos, s) == 0)
      return true;
  return false;
}

// Every file of the corpus a reader accepts, in manifest order.
inline std::vector<std::string> valid_shared_meshes() {
  std::vector<std::string> out;
  for (const auto& row : manifest())
    if (row.v != "-" && !must_refuse(row.file)) out.push_back(row.file);
  return out;
}

}  // namespace meshflow::testing
