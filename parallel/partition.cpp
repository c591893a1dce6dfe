#include "parallel/partition.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>

#include "mesh/errors.h"
#include "mesh/index_hash.h"
#include "mesh/mesh_io.h"
#include "mesh/part_files.h"
#include "parallel/bsp_partition.h"
#include "parallel/cell_ids.h"
#include "parallel/gid_index.h"
#include "parallel/scratch_files.h"

namespace meshflow::parallel {
namespace {

struct VertexRecord {  // a vertex in its cell's file
  std::uint32_t gid;
  float p[3];
};
struct TriangleRecord {  // a triangle in global ids
  std::uint32_t v[3];
};
struct RequestRecord {  // cell `from` needs a copy of vertex gid
  std::uint32_t gid, from;
  auto operator<=>(const RequestRecord&) const = default;
};
struct CopyRecord {  // the answer: a foreign vertex for the requesting cell
  std::uint32_t gid;
  float p[3];
  std::uint32_t partner;  // for the requesting part (mesh::PartFile::partner)
};

// Pass 1: bounding box and sample. A vertex is sampled when a hash of its index is a multiple of
// the stride (not every stride-th vertex: on a regular grid that sees a few columns only); the
// stride doubles, up to 1024 (about the thesis's 1:1000), whenever the sample grows past 2048,
// so every format (counts declared or not) samples alike.

class SampleSink : public mesh::MeshSink {
 public:
  void vertices(std::span<const mesh::Point> batch) override {
    for (const auto& p : batch) {
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
      const std::uint64_t h = mesh::index_hash(count);
      if ((h & (stride_ - 1)) == 0) samples.push_back({h, p});
      ++count;
      if (samples.size() >= 2048 && stride_ < 1024) {
        stride_ *= 2;
        std::erase_if(samples, [&](const auto& s) { return (s.first & (stride_ - 1)) != 0; });
      }
    }
  }
  void triangles(std::span<const mesh::Triangle>) override {}
  bool wants_triangles() const override { return false; }
  std::size_t stride() const { return stride_; }

  std::array<float, 3> lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  std::vector<std::pair<std::uint64_t, mesh::Point>> samples;
  std::uint64_t count = 0;

 private:
  std::size_t stride_ = 1;
};

// Pass 2: vertices and triangles to the cells' files.
class AssignSink : public mesh::MeshSink {
 public:
  AssignSink(const Bsp& bsp, const std::string& scratch, std::uint64_t expected_vertices,
             const std::function<void(double)>& progress)
      : bsp_(bsp),
        vertices_(scratch + "/V-", bsp.cells()),
        triangles_(scratch + "/T-", bsp.cells()),
        requests_(scratch + "/R-", bsp.cells()),
        cell_of_(std::make_unique<CellIds>(scratch + "/cells.bin")),
        expected_(expected_vertices),
        progress_(progress) {}
  void vertices(std::span<const mesh::Point> batch) override {
    for (const auto& p : batch) {
      if (cell_of_->size() >= 0xffffffffu) throw LimitExceeded("vertices in one mesh", 0xffffffffu, cell_of_->size() + 1);
      std::uint32_t cell = bsp_.locate(p);
      vertices_.add(cell, {static_cast<std::uint32_t>(cell_of_->size()), {p[0], p[1], p[2]}});
      cell_of_->push_back(cell);
    }
    if (progress_ && expected_) progress_(0.5 * std::min(1.0, double(cell_of_->size()) / double(expected_)));
  }
  void triangles(std::span<const mesh::Triangle> batch) override {
    for (const auto& t : batch) {
      CellIds& cell_of = *cell_of_;
      std::uint32_t c[3] = {cell_of[t[0]], cell_of[t[1]], cell_of[t[2]]};
      std::uint32_t owner;
      if (c[0] == c[1] || c[0] == c[2]) owner = c[0];
      else if (c[1] == c[2]) owner = c[1];
      else owner = *std::min_element(c, c + 3, [&](std::uint32_t a, std::uint32_t b) {
        return bsp_.centre(a) != bsp_.centre(b) ? bsp_.centre(a) < bsp_.centre(b) : a < b;
      });
      triangles_.add(owner, {{t[0], t[1], t[2]}});
      for (int k = 0; k < 3; ++k)
        if (c[k] != owner) requests_.add(c[k], {t[k], owner});
      ++triangle_count;
    }
  }
  void end() override {
    vertices_.flush();
    triangles_.flush();
    requests_.flush();
  }
  std::uint64_t vertex_count() const { return cell_of_->size(); }
  std::uint64_t triangles_in(std::size_t cell) const { return triangles_.count(cell); }
  void release() { cell_of_.reset(); }
  std::uint64_t triangle_count = 0;

 private:
  const Bsp& bsp_;
  Buckets<VertexRecord> vertices_;
  Buckets<TriangleRecord> triangles_;
  Buckets<RequestRecord> requests_;
  std::unique_ptr<CellIds> cell_of_;
  std::uint64_t expected_;
  const std::function<void(double)>& progress_;
};

class CountSink : public mesh::MeshSink {
 public:
  void begin(mesh::Format, std::int64_t v, std::int64_t) override { declared = v; }
  void vertices(std::span<const mesh::Point>) override {}
  void triangles(std::span<const mesh::Triangle>) override {}
  std::int64_t declared = -1;
};

// A cell's own vertices (ascending global ids: written in input order) indexed by global id.
GidIndex index_of(const std::vector<VertexRecord>& own) {
  std::vector<std::uint32_t> gids(own.size());
  for (std::size_t i = 0; i < own.size(); ++i) gids[i] = own[i].gid;
  return GidIndex(std::move(gids));
}

// Which of a cell's own vertices its own triangles use.
std::vector<std::uint8_t> referenced(const GidIndex& own, std::size_t count, const std::vector<TriangleRecord>& tris) {
  std::vector<std::uint8_t> used(count, 0);
  for (const auto& t : tris)
    for (std::uint32_t g : t.v) {
      std::size_t i = own.find(g);
      if (i != GidIndex::npos) used[i] = 1;
    }
  return used;
}

}  // namespace

std::string part_path(const std::string& dir, std::size_t p, bool simplified) {
  return dir + "/part-" + std::to_string(p) + (simplified ? ".simplified.mfp" : ".mfp");
}

std::string rem_path(const std::string& dir, std::size_t from, std::size_t to) {
  return dir + "/rem-" + std::to_string(from) + "-" + std::to_string(to) + ".bin";
}

std::string seam_path(const std::string& dir, std::size_t p, std::size_t q) {
  return dir + "/seam-" + std::to_string(p) + "-" + std::to_string(q) + ".mfp";
}

PartitionInfo partition_file(const std::string& input, std::size_t vertices_per_part, const std::string& dir,
                             const std::function<void(double)>& progress) {
  if (vertices_per_part == 0) throw InvalidInput("--vertices-per-part must be at least 1");
  auto start = std::chrono::steady_clock::now();
  PartitionInfo info;
  SampleSink sample;
  mesh::stream_mesh(input, sample);
  if (sample.count == 0) throw InvalidInput(input + ": the mesh has no vertices");
  info.diagonal = std::sqrt(std::pow(double(sample.hi[0]) - sample.lo[0], 2) + std::pow(double(sample.hi[1]) - sample.lo[1], 2) +
                            std::pow(double(sample.hi[2]) - sample.lo[2], 2));
  info.samples = sample.samples.size();
  std::vector<mesh::Point> points;
  points.reserve(sample.samples.size());
  for (const auto& s : sample.samples) points.push_back(s.second);
  sample.samples = {};
  Bsp bsp(std::move(points), sample.stride(), sample.lo, sample.hi, vertices_per_part);
  const std::size_t cells = bsp.cells();

  std::filesystem::create_directories(dir);
  // An earlier partition's seam sides would pass for this one's where this one has none.
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (entry.path().filename().string().rfind("seam-", 0) == 0) std::filesystem::remove(entry.path());
  const std::string scratch = dir + "/scratch";
  std::filesystem::remove_all(scratch);
  std::filesystem::create_directories(scratch);
  AssignSink assign(bsp, scratch, sample.count, progress);
  mesh::stream_mesh(input, assign);
  if (assign.vertex_count() != sample.count)
    throw IoError(input + ": the file changed while it was read (vertex count differs between passes)");
  assign.release();
  info.input_vertices = sample.count;
  info.input_triangles = assign.triangle_count;

  // Parts: the cells with triangles, in cell order.
  std::vector<std::uint32_t> part_of_cell(cells, ~0u);
  for (std::size_t c = 0; c < cells; ++c)
    if (assign.triangles_in(c) > 0) part_of_cell[c] = static_cast<std::uint32_t>(info.parts++);

  // The join: each cell answers the requests for its vertices.
  std::set<std::pair<std::uint32_t, std::uint32_t>> edges;  // between parts
  {
    Buckets<CopyRecord> copies(scratch + "/F-", cells);
    for (std::size_t c = 0; c < cells; ++c) {
      auto requests = load_records<RequestRecord>(scratch + "/R-" + std::to_string(c) + ".bin");
      if (requests.empty()) continue;
      auto own = load_records<VertexRecord>(scratch + "/V-" + std::to_string(c) + ".bin");
      const GidIndex own_index = index_of(own);
      auto used = referenced(own_index, own.size(), load_records<TriangleRecord>(scratch + "/T-" + std::to_string(c) + ".bin"));
      std::sort(requests.begin(), requests.end());
      requests.erase(std::unique(requests.begin(), requests.end()), requests.end());
      std::vector<std::uint32_t> users;
      for (std::size_t i = 0; i < requests.size();) {
        std::size_t j = i;
        while (j < requests.size() && requests[j].gid == requests[i].gid) ++j;
        std::size_t at = own_index.find(requests[i].gid);
        if (at == GidIndex::npos) throw std::logic_error("partition: a requested vertex is not in its cell's file");
        users.clear();
        if (used[at]) users.push_back(part_of_cell[c]);
        for (std::size_t k = i; k < j; ++k) users.push_back(part_of_cell[requests[k].from]);
        const bool shared = users.size() >= 2;
        for (std::size_t k = i; k < j; ++k) {
          // The requester's partner: the one other user, or the 3+ flag.
          const std::uint32_t me = part_of_cell[requests[k].from];
          const std::uint32_t partner = users.size() < 2 ? mesh::kNotShared
                                        : users.size() > 2 ? mesh::kSharedBy3
                                                           : (users[0] == me ? users[1] : users[0]);
          copies.add(requests[k].from, {requests[i].gid, {own[at].p[0], own[at].p[1], own[at].p[2]}, partner});
        }
        if (shared) {
          ++info.shared_vertices;
          if (users.size() >= 3) ++info.shared_by_3_or_more;
          for (std::uint32_t a : users)
            for (std::uint32_t b : users)
              if (a < b) edges.emplace(a, b);
        }
        i = j;
      }
    }
  }
  info.adjacency.assign(info.parts, {});
  for (auto [a, b] : edges) info.adjacency[a].push_back(b), info.adjacency[b].push_back(a);
  for (auto& n : info.adjacency) std::sort(n.begin(), n.end());

  // The part files.
  for (std::size_t c = 0; c < cells; ++c) {
    const std::string id = std::to_string(c) + ".bin";
    if (part_of_cell[c] != ~0u) {
      auto own = load_records<VertexRecord>(scratch + "/V-" + id);
      auto tris = load_records<TriangleRecord>(scratch + "/T-" + id);
      const GidIndex own_index = index_of(own);
      auto used = referenced(own_index, own.size(), tris);
      // An own vertex requested by one other part has it as partner; by two or more, the 3+ flag.
      std::vector<std::uint32_t> partner(own.size(), mesh::kNotShared);
      for (const auto& r : load_records<RequestRecord>(scratch + "/R-" + id)) {
        std::size_t at = own_index.find(r.gid);
        if (at == GidIndex::npos) throw std::logic_error("partition: a requested vertex is not in its cell's file");
        const std::uint32_t from = part_of_cell[r.from];
        if (partner[at] == mesh::kNotShared) partner[at] = from;
        else if (partner[at] != from) partner[at] = mesh::kSharedBy3;
      }
      auto copies = load_records<CopyRecord>(scratch + "/F-" + id);
      std::sort(copies.begin(), copies.end(), [](const CopyRecord& a, const CopyRecord& b) { return a.gid < b.gid; });
      mesh::PartFile part;
      part.global_ids.reserve(own.size() + copies.size());
      part.positions.reserve(own.size() + copies.size());
      part.partner.reserve(own.size() + copies.size());
      std::size_t i = 0, k = 0;
      while (i < own.size() || k < copies.size()) {
        if (i < own.size() && !used[i]) {
          ++i;
          continue;
        }
        if (k == copies.size() || (i < own.size() && own[i].gid < copies[k].gid)) {
          part.global_ids.push_back(own[i].gid);
          part.positions.push_back({own[i].p[0], own[i].p[1], own[i].p[2]});
          part.partner.push_back(partner[i]);
          ++i;
        } else {
          part.global_ids.push_back(copies[k].gid);
          part.positions.push_back({copies[k].p[0], copies[k].p[1], copies[k].p[2]});
          part.partner.push_back(copies[k].partner);
          ++k;
        }
      }
      // Every corner is an own vertex or a copy, and the ids came from 32-bit records.
      const GidIndex local_of(std::vector<std::uint32_t>(part.global_ids.begin(), part.global_ids.end()));
      part.triangles.reserve(tris.size());
      for (const auto& t : tris)
        part.triangles.push_back({static_cast<mesh::Index>(local_of.find(t.v[0])), static_cast<mesh::Index>(local_of.find(t.v[1])),
                                  static_cast<mesh::Index>(local_of.find(t.v[2]))});
      mesh::write_part(part, part_path(dir, part_of_cell[c], false));
      for (const auto& [q, side] : mesh::seam_sides(part)) mesh::write_part(side, seam_path(dir, part_of_cell[c], q));
    }
    for (const char* kind : {"V-", "T-", "R-", "F-"}) std::filesystem::remove(scratch + "/" + kind + id);
    if (progress) progress(0.5 + 0.5 * double(c + 1) / double(cells));
  }
  std::filesystem::remove_all(scratch);
  write_partition_info(dir, info);
  info.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return info;
}

void write_partition_info(const std::string& dir, const PartitionInfo& info) {
  std::ofstream out(dir + "/partition.txt");
  out << mesh::encode_parts_index({info.parts, info.diagonal, info.adjacency});
  if (!out) throw IoError(dir + "/partition.txt: cannot write");
}

PartitionInfo read_partition_info(const std::string& dir) {
  const std::string path = dir + "/partition.txt";
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InvalidInput(path + ": cannot open (written by meshflow partition)");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  mesh::PartsIndex index = mesh::decode_parts_index(text, path);
  PartitionInfo info;
  info.parts = index.parts, info.diagonal = index.diagonal, info.adjacency = std::move(index.adjacency);
  return info;
}

}  // namespace meshflow::parallel
