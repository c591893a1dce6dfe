#pragma once
// Simplify: quadric error metric edge collapse (Garland & Heckbert 1997) with optimal placement
// and the thesis's adaptive stop (Cabiddu, ch. 9): collapses go cheapest first, ranked by the
// RMS distance of the new vertex to the planes of the triangles merged into it,
//     rms = sqrt(Q(v) / A),   Q = sum over merged triangles of area * (n.v + d)^2, A = sum of area,
// and stop where the cheapest would exceed `max_error` (absolute), so flat parts decimate more
// than detailed ones; or at `target_vertices`. Boundary edges get constraint planes, a boundary
// vertex only collapses along its boundary, loops of three edges are never closed; every collapse
// keeps a manifold neighbourhood manifold (link condition) and flips no triangle. Non-manifold
// edges and vertices are left alone.

#include <atomic>
#include <cstddef>
#include <functional>

#include "mesh/mesh.h"

namespace meshflow::services {

struct SimplifyParams {
  double max_error = 0;             // absolute distance; 0: no error stop
  std::size_t target_vertices = 0;  // 0: no vertex target
  std::function<void(double)> progress;
  const std::atomic<bool>* cancel = nullptr;
};

struct SimplifyResult {
  mesh::Mesh output;        // surviving referenced vertices in ascending input id order
  std::size_t collapses = 0;
  double max_rms_error = 0;  // the largest rms of a collapse made
};

// \throws InvalidInput when neither a max_error nor a target is given.
SimplifyResult simplify(const mesh::Mesh& input, const SimplifyParams& params);

}  // namespace meshflow::services
