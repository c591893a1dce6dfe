#pragma once
// Simplify: quadric error metric edge collapse (Garland & Heckbert 1997) with optimal placement,
// cheapest quadric error first, and the thesis's adaptive stop (Cabiddu, ch. 9) at a max error E:
// a collapse is made only while the RMS distance of the new vertex to the planes of the triangles
// merged into it stays within E,
//     rms = sqrt(Q(v) / A),   Q = sum over merged triangles of area * (n.v + d)^2, A = sum of area,
// and the run stops where the cheapest Q exceeds max_quadric(E), the Q of RMS E over a square of
// side 32 E: a vertex standing for more surface than that must be proportionally more accurate.
// The RMS bound alone merges flat regions until they too are at E over large areas, which cost
// 4-11 % of mean error at equal vertex count on the shared scans (bench/README.md); with both, so
// that flat parts still decimate more than detailed ones, 0-3 %. Or the run stops at
// `target_vertices`.
// Boundary edges get constraint planes, a boundary vertex only collapses along its boundary,
// loops of three edges are never closed; every collapse keeps a manifold neighbourhood manifold
// (link condition) and flips no triangle. Non-manifold edges and vertices are left alone.

#include <array>
#include <atomic>
#include <cstddef>
#include <functional>
#include <utility>
#include <vector>

#include "mesh/mesh.h"

namespace meshflow::services {

// The other side of a seam, which the mesh being simplified does not hold (parallel/: the
// partner part). Asked before each half-edge collapse of a seam vertex (SimplifyParams::
// seam_partner), with the apex of the edge's triangle here and the sorted neighbours of both
// ends here; told after each one made.
class SeamSide {
 public:
  virtual ~SeamSide() = default;
  virtual bool allows(mesh::Index drop, mesh::Index keep, mesh::Index apex, const std::vector<mesh::Index>& keep_neighbours,
                      const std::vector<mesh::Index>& drop_neighbours) = 0;
  virtual void collapsed(mesh::Index drop, mesh::Index keep) = 0;
};

struct SimplifyParams {
  double max_error = 0;             // absolute distance (RMS), with max_quadric(max_error); 0: no error stop
  std::size_t target_vertices = 0;  // 0: no vertex target
  std::function<void(double)> progress;
  const std::atomic<bool>* cancel = nullptr;
  // For simplification in pieces (parallel/). `locked` vertices are never moved nor removed (a
  // neighbour may collapse into one, which stays in place), and a border edge between two locked
  // vertices is a seam: it gets no constraint plane.
  const std::vector<bool>* locked = nullptr;
  // Start from these per-vertex quadrics instead of the triangles' planes; border planes are
  // then added only on border edges whose two ends are flagged in `seam` (edges that had none).
  const std::vector<std::array<double, 11>>* quadrics = nullptr;
  const std::vector<bool>* seam = nullptr;
  bool export_quadrics = false;
  // The thesis's seams (Rem files, parallel/): per vertex, the one other part a shared vertex
  // may be removed for (kNoPartner otherwise). Such a vertex only goes by a half-edge collapse
  // along a border edge onto a neighbour with the same partner, which stays where it is; an
  // edge from it to any other vertex keeps it, in place. Each such removal is logged in
  // SimplifyResult::seam_collapses.
  const std::vector<std::uint32_t>* seam_partner = nullptr;
  SeamSide* seam_side = nullptr;  // with seam_partner: the partner's side, consulted
  // Merges replayed before simplifying: per vertex, the vertex it was merged into (itself if
  // none; final targets, no chains). Triangles are renamed, the degenerate ones dropped, and a
  // merged vertex's quadric goes to its target.
  const std::vector<mesh::Index>* merged_into = nullptr;
};

constexpr std::uint32_t kNoPartner = 0xFFFFFFFFu;

// The quadric bound that goes with a max error E (see the top of this file).
constexpr double max_quadric(double max_error) {
  const double side = 32 * max_error;
  return max_error * max_error * side * side;
}

struct SimplifyResult {
  mesh::Mesh output;        // surviving referenced vertices in ascending input id order
  std::size_t collapses = 0;
  double max_rms_error = 0;  // the largest rms of a collapse made
  std::vector<mesh::Index> source_ids;            // input id of each output vertex
  std::vector<std::array<double, 11>> quadrics;   // of each output vertex, when exported
  // With seam_partner: (removed, kept) input ids of the half-edge collapses of seam vertices, in order.
  std::vector<std::pair<mesh::Index, mesh::Index>> seam_collapses;
};

// \throws InvalidInput when neither a max_error nor a target is given.
SimplifyResult simplify(const mesh::Mesh& input, const SimplifyParams& params);

}  // namespace meshflow::services
