// Peer for bench/simplify_bench.sh: meshoptimizer's meshopt_simplify (never moves vertices),
// stopping at a triangle count. Usage: meshopt_simplify IN OUT TARGET_VERTICES
#include <meshoptimizer.h>

#include <cstdio>
#include <string>

#include "mesh/mesh_io.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: meshopt_simplify IN OUT TARGET_VERTICES\n");
    return 2;
  }
  meshflow::mesh::Mesh in = meshflow::mesh::read_mesh(argv[1]);
  std::vector<unsigned int> indices;
  for (auto& t : in.triangles) indices.insert(indices.end(), t.begin(), t.end());
  std::size_t target_indices = 3 * 2 * std::stoul(argv[3]);
  std::vector<unsigned int> out_indices(indices.size());
  float error = 0;
  std::size_t n = meshopt_simplify(out_indices.data(), indices.data(), indices.size(), &in.positions[0][0],
                                   in.positions.size(), sizeof(float) * 3, target_indices, 1.0f, 0, &error);
  out_indices.resize(n);
  // Keep only the vertices still used, in their order.
  std::vector<unsigned int> remap(in.positions.size(), ~0u);
  meshflow::mesh::Mesh out;
  for (unsigned int& i : out_indices) {
    if (remap[i] == ~0u) {
      remap[i] = static_cast<unsigned int>(out.positions.size());
      out.positions.push_back(in.positions[i]);
    }
    i = remap[i];
  }
  for (std::size_t k = 0; k < n; k += 3) out.triangles.push_back({out_indices[k], out_indices[k + 1], out_indices[k + 2]});
  meshflow::mesh::write_mesh(out, argv[2]);
  return 0;
}
