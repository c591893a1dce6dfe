#pragma once
// Tiny meshes whose measures can be derived by hand, for the unit tests.
#include <cmath>
#include <filesystem>
#include <string>

#include "mesh/mesh.h"

namespace meshflow::testing {

using mesh::Mesh;

// Unit cube [0,1]^3, 8 vertices, 12 outward CCW triangles.
inline Mesh cube(float offset_x = 0) {
  Mesh m;
  for (int i = 0; i < 8; ++i)
    m.positions.push_back({float(i & 1) + offset_x, float((i >> 1) & 1), float((i >> 2) & 1)});
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

// Regular-ish tetrahedron on the unit axes: (0,0,0), (1,0,0), (0,1,0), (0,0,1), outward.
inline Mesh tetrahedron() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

// The unit square in z = 0 as two triangles: one boundary loop of 4 edges.
inline Mesh open_square() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

// A Möbius strip: a band of `n` quads (2n triangles) with a half twist; one boundary loop,
// not orientable.
inline Mesh moebius(int n = 12) {
  Mesh m;
  const double pi = 3.14159265358979323846;
  for (int i = 0; i < n; ++i) {
    double t = 2 * pi * i / n;
    for (double s : {-0.3, 0.3}) {
      double r = 1 + s * std::cos(t / 2);
      m.positions.push_back({float(r * std::cos(t)), float(r * std::sin(t)), float(s * std::sin(t / 2))});
    }
  }
  for (int i = 0; i < n; ++i) {
    mesh::Index a = 2 * i, b = 2 * i + 1;
    mesh::Index c = 2 * ((i + 1) % n), d = c + 1;
    if (i == n - 1) std::swap(c, d);  // the half twist glues the band flipped
    m.triangles.push_back({a, c, b});
    m.triangles.push_back({b, c, d});
  }
  return m;
}

// Two unit cubes sharing the edge x = 1, y = 1 (z from 0 to 1): that edge has four triangles.
inline Mesh two_cubes_sharing_an_edge() {
  Mesh m = cube();
  Mesh second = cube();
  // Move the second cube to [1,2] x [1,2] x [0,1] and weld its edge (1,1,z) onto the first.
  std::vector<mesh::Index> remap(8);
  for (int i = 0; i < 8; ++i) {
    mesh::Point p = second.positions[i];
    p[0] += 1, p[1] += 1;
    if (p[0] == 1 && p[1] == 1) {
      remap[i] = (p[2] == 0) ? 3 : 7;  // (1,1,0) and (1,1,1) of the first cube
    } else {
      remap[i] = static_cast<mesh::Index>(m.positions.size());
      m.positions.push_back(p);
    }
  }
  for (auto t : second.triangles) m.triangles.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
  return m;
}

inline std::string shared_meshes() { return MESHFLOW_SHARED_MESHES; }

// A fresh temporary directory removed when the object goes.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    char tmpl[] = "/tmp/meshflow-test-XXXXXX";
    path = mkdtemp(tmpl);
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
  std::string file(const std::string& name) const { return (path / name).string(); }
};

}  // namespace meshflow::testing
