#pragma once
// The indexed triangle mesh every layer shares: float32 positions, 32-bit vertex ids.
// It holds input as read: non-manifold edges, repeated indices, unreferenced vertices and
// inconsistent orientation are all representable; nothing is fixed on load.

#include <array>
#include <cstdint>
#include <vector>

namespace meshflow::mesh {

using Index = std::uint32_t;
using Point = std::array<float, 3>;
using Triangle = std::array<Index, 3>;

struct Mesh {
  std::vector<Point> positions;       // #V x 3, float32 (DESIGN §6: every hash is over these)
  std::vector<Triangle> triangles;    // #T x 3, 0-based vertex ids, counter-clockwise = front

  std::size_t num_vertices() const { return positions.size(); }
  std::size_t num_triangles() const { return triangles.size(); }
  bool empty() const { return triangles.empty() && positions.empty(); }
  bool operator==(const Mesh&) const = default;
};

// Axis-aligned bounding box of the positions (of all vertices, referenced or not).
struct Box {
  std::array<double, 3> min{0, 0, 0};
  std::array<double, 3> max{0, 0, 0};
  double diagonal() const;
};
Box bounding_box(const Mesh& mesh);

}  // namespace meshflow::mesh
