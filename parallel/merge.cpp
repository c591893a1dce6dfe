#include "parallel/merge.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <unordered_map>

#include "mesh/canonical_ply.h"
#include "mesh/errors.h"
#include "mesh/part_files.h"
#include "parallel/partition.h"
#include "services/simplify.h"

namespace meshflow::parallel {
namespace {

using mesh::Index;

double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// Which triangles of a part are in the seam band, and which vertices they use.
struct Band {
  std::vector<std::uint8_t> triangle;  // 1: in the band
  std::vector<std::uint8_t> vertex;    // 1: used by a band triangle; 2: also by a kept one
};

Band seam_band(const mesh::PartFile& part) {
  const std::size_t V = part.positions.size(), T = part.triangles.size();
  Band b{std::vector<std::uint8_t>(T, 0), std::vector<std::uint8_t>(V, 0)};
  std::vector<std::uint8_t> near(V, 0);
  for (std::size_t v = 0; v < V; ++v) near[v] = part.shared(v);
  for (int ring = 0; ring < kSeamRings; ++ring) {
    for (std::size_t t = 0; t < T; ++t)
      for (Index v : part.triangles[t])
        if (near[v] == 1) b.triangle[t] = 1;
    for (std::size_t t = 0; t < T; ++t)
      if (b.triangle[t])
        for (Index v : part.triangles[t]) near[v] = 1;
  }
  for (std::size_t t = 0; t < T; ++t)
    for (Index v : part.triangles[t]) b.vertex[v] |= b.triangle[t] ? 1 : 2;
  // vertex: 0 unused, 1 band only, 2 kept only, 3 both (locked in the band)
  return b;
}

// Two triangles on the same three vertices with opposite orientations: a fin, left where the
// half-edge collapses of two parts' Rem files closed a seam loop of three edges (each part saw
// only its own side). A collapse done in one piece would have removed both; so does this.
std::size_t remove_fins(std::vector<mesh::Triangle>& triangles) {
  auto key = [](const mesh::Triangle& t) {
    std::array<Index, 3> k = t;
    std::sort(k.begin(), k.end());
    return k;
  };
  std::vector<std::uint32_t> order(triangles.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return key(triangles[a]) < key(triangles[b]); });
  // Orientation: the cyclic order, as a rotation to the smallest vertex first.
  auto rotated = [](const mesh::Triangle& t) {
    int m = t[0] < t[1] ? (t[0] < t[2] ? 0 : 2) : (t[1] < t[2] ? 1 : 2);
    return std::array<Index, 3>{t[m], t[(m + 1) % 3], t[(m + 2) % 3]};
  };
  std::vector<std::uint8_t> gone(triangles.size(), 0);
  std::size_t pairs = 0;
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j < order.size() && key(triangles[order[j]]) == key(triangles[order[i]])) ++j;
    for (std::size_t a = i; a < j; ++a)
      for (std::size_t b = a + 1; b < j && !gone[order[a]]; ++b)
        if (!gone[order[b]] && rotated(triangles[order[a]]) != rotated(triangles[order[b]])) {
          gone[order[a]] = gone[order[b]] = 1;
          ++pairs;
        }
    i = j;
  }
  if (pairs) {
    std::size_t n = 0;
    for (std::size_t t = 0; t < triangles.size(); ++t)
      if (!gone[t]) triangles[n++] = triangles[t];
    triangles.resize(n);
  }
  return pairs;
}

mesh::PartFile load_simplified(const std::string& dir, std::size_t p) {
  const std::string path = part_path(dir, p, true);
  mesh::PartFile part = mesh::read_part(path);
  if (part.quadrics.size() != part.positions.size())
    throw InvalidInput(path + ": a simplified part must carry its quadrics");
  return part;
}

class OutputFile {
 public:
  OutputFile(const std::string& path, std::uint64_t offset) : path_(path) {
    f_ = std::fopen(path.c_str(), "r+b");
    if (!f_ || std::fseek(f_, static_cast<long>(offset), SEEK_SET) != 0) throw IoError(path + ": cannot open for writing");
    std::setvbuf(f_, nullptr, _IOFBF, 1 << 20);
  }
  ~OutputFile() {
    if (f_) std::fclose(f_);
  }
  void write(const void* data, std::size_t n) {
    if (std::fwrite(data, 1, n, f_) != n) throw IoError(path_ + ": cannot write (disk full?)");
  }
  void vertex(const mesh::Point& p) { write(p.data(), 12); }
  void triangle(Index a, Index b, Index c) {
    std::uint8_t rec[13] = {3};
    std::int32_t v[3] = {static_cast<std::int32_t>(a), static_cast<std::int32_t>(b), static_cast<std::int32_t>(c)};
    std::memcpy(rec + 1, v, 12);
    write(rec, 13);
  }
  void close() {
    std::FILE* f = f_;
    f_ = nullptr;
    if (std::fclose(f) != 0) throw IoError(path_ + ": cannot write (disk full?)");
  }

 private:
  std::string path_;
  std::FILE* f_ = nullptr;
};

}  // namespace

MergeReport merge_parts(const std::string& dir, std::size_t parts, double max_error_abs, const std::string& out,
                        const std::function<void(const std::string&, double)>& progress) {
  if (!(max_error_abs > 0)) throw InvalidInput("--max-error must be > 0");
  MergeReport report;
  auto start = std::chrono::steady_clock::now();
  // 1. The band, and the counts of what stays as it is.
  std::unordered_map<std::uint64_t, Index> band_id;
  mesh::Mesh band;
  std::vector<std::array<double, 11>> quadrics;
  std::vector<bool> band_seam, band_locked;
  std::uint64_t kept_vertices = 0, kept_triangles = 0;
  for (std::size_t p = 0; p < parts; ++p) {
    mesh::PartFile part = load_simplified(dir, p);
    Band b = seam_band(part);
    std::vector<Index> local(part.positions.size(), 0);
    for (std::size_t v = 0; v < part.positions.size(); ++v) {
      if (b.vertex[v] == 2) ++kept_vertices;
      if (!(b.vertex[v] & 1)) continue;
      auto [it, added] = band_id.try_emplace(part.global_ids[v], static_cast<Index>(band.positions.size()));
      if (added) {
        band.positions.push_back(part.positions[v]);
        quadrics.push_back(part.quadrics[v]);
        band_seam.push_back(part.shared(v));
        band_locked.push_back(b.vertex[v] == 3);
      } else {
        if (!part.shared(v)) throw InvalidInput(part_path(dir, p, true) + ": vertex " + std::to_string(part.global_ids[v]) +
                                                " is in two parts but not flagged shared");
        for (int k = 0; k < 11; ++k) quadrics[it->second][k] += part.quadrics[v][k];
        if (b.vertex[v] == 3) band_locked[it->second] = true;
      }
      local[v] = it->second;
    }
    for (std::size_t t = 0; t < part.triangles.size(); ++t) {
      const auto& tri = part.triangles[t];
      if (b.triangle[t]) band.triangles.push_back({local[tri[0]], local[tri[1]], local[tri[2]]});
      else ++kept_triangles;
    }
    if (progress) progress("seams", 0.3 * double(p + 1) / double(parts));
  }
  report.fins_removed = remove_fins(band.triangles);
  report.band_vertices = band.positions.size();
  report.band_triangles = band.triangles.size();

  // 2. The band simplified; its locked vertices all stay (even one the simplifier left without a triangle).
  services::SimplifyResult simplified;
  if (!band.triangles.empty()) {
    services::SimplifyParams sp;
    sp.max_error = max_error_abs;
    sp.quadrics = &quadrics;
    sp.seam = &band_seam;
    sp.locked = &band_locked;
    if (progress) sp.progress = [&](double f) { progress("seams", 0.3 + 0.7 * f); };
    simplified = services::simplify(band, sp);
  }
  quadrics = {};
  std::vector<Index> band_out(band.positions.size(), ~0u);
  std::vector<mesh::Point> out_band_positions = std::move(simplified.output.positions);
  for (std::size_t i = 0; i < simplified.source_ids.size(); ++i) band_out[simplified.source_ids[i]] = static_cast<Index>(i);
  for (std::size_t v = 0; v < band.positions.size(); ++v)
    if (band_locked[v] && band_out[v] == ~0u) {
      band_out[v] = static_cast<Index>(out_band_positions.size());
      out_band_positions.push_back(band.positions[v]);
    }
  for (auto& [gid, id] : band_id) id = band_out[id];  // now: output index, or ~0u when removed
  band = {};
  report.seams_seconds = since(start);

  // 3. The output: band vertices first, then each part's kept vertices; triangles likewise.
  start = std::chrono::steady_clock::now();
  report.output_vertices = out_band_positions.size() + kept_vertices;
  report.output_triangles = simplified.output.triangles.size() + kept_triangles;
  if (report.output_vertices > 0x7fffffffu) throw LimitExceeded("vertices in a PLY output", 0x7fffffffu, report.output_vertices);
  const std::string tmp = out + ".tmp";
  const std::string header = mesh::canonical_ply_header(report.output_vertices, report.output_triangles);
  {
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f || std::fwrite(header.data(), 1, header.size(), f) != header.size() || std::fclose(f) != 0)
      throw IoError(tmp + ": cannot write");
  }
  OutputFile vertices(tmp, header.size()), faces(tmp, header.size() + 12 * report.output_vertices);
  for (const auto& p : out_band_positions) vertices.vertex(p);
  for (const auto& t : simplified.output.triangles) faces.triangle(t[0], t[1], t[2]);
  Index next = static_cast<Index>(out_band_positions.size());
  out_band_positions = {};
  simplified = {};
  for (std::size_t p = 0; p < parts; ++p) {
    mesh::PartFile part = load_simplified(dir, p);
    Band b = seam_band(part);
    std::vector<Index> to_out(part.positions.size(), ~0u);
    for (std::size_t v = 0; v < part.positions.size(); ++v) {
      if (b.vertex[v] == 2) {
        vertices.vertex(part.positions[v]);
        to_out[v] = next++;
      } else if (b.vertex[v] == 3) {
        to_out[v] = band_id.at(part.global_ids[v]);
      }
    }
    for (std::size_t t = 0; t < part.triangles.size(); ++t)
      if (!b.triangle[t]) {
        const auto& tri = part.triangles[t];
        faces.triangle(to_out[tri[0]], to_out[tri[1]], to_out[tri[2]]);
      }
    if (progress) progress("merge", double(p + 1) / double(parts));
  }
  if (next != report.output_vertices) throw std::logic_error("merge: the parts changed between the two passes");
  vertices.close();
  faces.close();
  std::filesystem::rename(tmp, out);
  report.merge_seconds = since(start);
  return report;
}

}  // namespace meshflow::parallel
