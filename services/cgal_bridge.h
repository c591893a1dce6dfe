#pragma once
// Everything meshflow asks of CGAL, behind plain types (DESIGN §2): CGAL's headers cost
// minutes of compile time and gigabytes of compiler memory, so they stay in cgal_bridge.cpp.

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "mesh/mesh.h"

namespace meshflow::services::cgal {

using mesh::Index;
using mesh::Point;

// Exact orientation predicates on float32 coordinates.
bool collinear(const Point& a, const Point& b, const Point& c);

// One filled hole: new vertices (appended after the mesh's) and new triangles, whose ids are
// either existing vertex ids or mesh.positions.size() + k for the k-th new vertex.
struct HoleFill {
  std::vector<Point> vertices;
  std::vector<mesh::Triangle> triangles;
};

// Fills boundary loops with Liepa's method (CGAL triangulate_refine_and_fair_hole; falling
// back to triangulate+refine, then to a plain triangulation, then to a triangulation of the
// loop as a polyline where every triangulation inside the mesh would repeat an edge). Loops are
// found on a halfedge copy of the referenced triangles (non-manifold vertices duplicated);
// `skip_largest` leaves the loop with the most edges open (height fields). `boundary_edges`
// (sorted keys min << 32 | max), when given, are the true boundary edges: `mesh` is then a
// neighbourhood of them cut out of a larger mesh, and loops along the cut are left alone.
HoleFill fill_holes(const mesh::Mesh& mesh, bool skip_largest, std::span<const std::uint64_t> boundary_edges = {});

// Metro-style distance (DESIGN §1 `compare`): samples spread uniformly by area on each surface,
// distance of each to the other surface by an AABB tree. Distances are absolute.
struct Distance {
  double mean_ab = 0, max_ab = 0, mean_ba = 0, max_ba = 0;
};
Distance surface_distance(const mesh::Mesh& a, const mesh::Mesh& b, std::size_t samples_a,
                          std::size_t samples_b, std::uint64_t seed);

// Distances from points to one surface, for inputs streamed point by point.
class DistanceToSurface {
 public:
  explicit DistanceToSurface(const mesh::Mesh& surface);
  ~DistanceToSurface();
  double operator()(const Point& p) const;  // 0 when the surface has no triangle
 private:
  struct Tree;
  std::unique_ptr<Tree> tree_;
};

}  // namespace meshflow::services::cgal
