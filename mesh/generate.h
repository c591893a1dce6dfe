#pragma once
// Synthetic meshes of any size, streamed straight to disk as canonical binary PLY: memory does
// not grow with the number of triangles. Deterministic for a given seed.
//  - terrain: a fractal height field (fBm of value noise) over a regular grid, one boundary
//    loop, one component, manifold; each cell split along its (i,j)-(i+1,j+1) diagonal, CCW
//    seen from +z.
//  - sphere: a closed bumpy surface (a latitude-longitude sphere whose radius is displaced by
//    3D fBm), watertight, manifold, one component, outward-oriented.

#include <cstdint>
#include <functional>
#include <string>

namespace meshflow::mesh {

enum class Shape { Terrain, Sphere };

struct GenerateParams {
  Shape shape = Shape::Terrain;
  std::uint64_t triangles = 1'000'000;  // approximate target; the exact count is reported
  std::uint64_t seed = 1;
  std::function<void(double)> progress;  // fraction done, called now and then
};

struct GenerateResult {
  std::uint64_t vertices = 0;
  std::uint64_t triangles = 0;
};

// Writes the mesh to `path` (via path.tmp, renamed on success). \throws InvalidInput for a
// triangle count below 2 or beyond 32-bit vertex ids, IoError when writing fails.
GenerateResult generate_mesh(const GenerateParams& params, const std::string& path);

}  // namespace meshflow::mesh
