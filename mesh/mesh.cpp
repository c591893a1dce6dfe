#include "mesh/mesh.h"

#include <algorithm>
#include <cmath>

namespace meshflow::mesh {

double Box::diagonal() const {
  double dx = max[0] - min[0], dy = max[1] - min[1], dz = max[2] - min[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

Box bounding_box(const Mesh& mesh) {
  Box box;
  if (mesh.positions.empty()) return box;
  for (int k = 0; k < 3; ++k) box.min[k] = box.max[k] = mesh.positions[0][k];
  for (const Point& p : mesh.positions) {
    for (int k = 0; k < 3; ++k) {
      box.min[k] = std::min<double>(box.min[k], p[k]);
      box.max[k] = std::max<double>(box.max[k], p[k]);
    }
  }
  return box;
}

}  // namespace meshflow::mesh
