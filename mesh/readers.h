#pragma once
// The format readers behind stream_mesh() (mesh/mesh_io.h). Each reads from an InputStream
// positioned at the start of the (decompressed) content and pushes batches into the sink.

#include <vector>

#include "mesh/input_stream.h"
#include "mesh/mesh_io.h"

namespace meshflow::mesh {

ReadInfo read_ply(InputStream& in, MeshSink& sink);
ReadInfo read_off(InputStream& in, MeshSink& sink);
ReadInfo read_obj(InputStream& in, MeshSink& sink);
ReadInfo read_stl(InputStream& in, MeshSink& sink);

// Collects vertices and triangles into batches for the sink.
class BatchWriter {
 public:
  static constexpr std::size_t kBatch = 1 << 16;
  explicit BatchWriter(MeshSink& sink) : sink_(sink) {
    vertices_.reserve(kBatch);
    triangles_.reserve(kBatch);
  }
  void vertex(const Point& p) {
    vertices_.push_back(p);
    if (vertices_.size() == kBatch) flush_vertices();
  }
  void triangle(const Triangle& t) {
    triangles_.push_back(t);
    if (triangles_.size() == kBatch) flush_triangles();
  }
  // Polygon (v0, v1, ..., vn-1) as the fan (v0, vi, vi+1).
  void polygon(const Index* v, std::size_t n) {
    for (std::size_t i = 1; i + 1 < n; ++i) triangle({v[0], v[i], v[i + 1]});
  }
  void flush_vertices() {
    if (!vertices_.empty()) sink_.vertices(vertices_);
    vertices_.clear();
  }
  void flush_triangles() {
    if (!triangles_.empty()) sink_.triangles(triangles_);
    triangles_.clear();
  }
  void flush() {
    flush_vertices();
    flush_triangles();
  }

 private:
  MeshSink& sink_;
  std::vector<Point> vertices_;
  std::vector<Triangle> triangles_;
};

// The largest count worth reserving for `declared` records of at least `min_bytes` each:
// never more than the input can hold (a header may lie: malformed/OutOfMemory.off).
std::uint64_t plausible_count(const InputStream& in, std::uint64_t declared, std::uint64_t min_bytes);

}  // namespace meshflow::mesh
