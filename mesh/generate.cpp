#include "mesh/generate.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <vector>

#include "mesh/canonical_ply.h"
#include "mesh/errors.h"

namespace meshflow::mesh {
namespace {

std::uint64_t mix(std::uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdull;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ull;
  x ^= x >> 33;
  return x;
}

// Lattice value in [-1, 1] for an integer point.
double lattice(std::int64_t x, std::int64_t y, std::int64_t z, std::uint64_t seed) {
  std::uint64_t h = mix(static_cast<std::uint64_t>(x) * 0x9E3779B97F4A7C15ull ^
                        mix(static_cast<std::uint64_t>(y) + 0x632BE59BD9B4E019ull) ^
                        mix(static_cast<std::uint64_t>(z) * 0x85EBCA77C2B2AE63ull + seed));
  return static_cast<double>(h >> 11) / static_cast<double>(1ull << 52) - 1.0;
}

double smooth(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }

// Trilinear value noise with quintic fade.
double value_noise(double x, double y, double z, std::uint64_t seed) {
  double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy),
       iz = static_cast<std::int64_t>(fz);
  double u = smooth(x - fx), v = smooth(y - fy), w = smooth(z - fz);
  auto lerp = [](double a, double b, double t) { return a + (b - a) * t; };
  double c00 = lerp(lattice(ix, iy, iz, seed), lattice(ix + 1, iy, iz, seed), u);
  double c10 = lerp(lattice(ix, iy + 1, iz, seed), lattice(ix + 1, iy + 1, iz, seed), u);
  double c01 = lerp(lattice(ix, iy, iz + 1, seed), lattice(ix + 1, iy, iz + 1, seed), u);
  double c11 = lerp(lattice(ix, iy + 1, iz + 1, seed), lattice(ix + 1, iy + 1, iz + 1, seed), u);
  return lerp(lerp(c00, c10, v), lerp(c01, c11, v), w);
}

// Fractal Brownian motion: octaves of value noise, each twice the frequency, half the amplitude.
double fbm(double x, double y, double z, std::uint64_t seed, int octaves) {
  double sum = 0, amplitude = 0.5, frequency = 1;
  for (int o = 0; o < octaves; ++o) {
    sum += amplitude * value_noise(x * frequency, y * frequency, z * frequency, seed + o);
    amplitude *= 0.5;
    frequency *= 2;
  }
  return sum;
}

class PlyStreamWriter {
 public:
  PlyStreamWriter(const std::string& path, std::uint64_t vertices, std::uint64_t triangles)
      : path_(path), tmp_(path + ".tmp") {
    file_ = std::fopen(tmp_.c_str(), "wb");
    if (!file_) throw IoError(path + ": cannot create " + tmp_);
    buffer_.reserve(kBuffer);
    std::string header = canonical_ply_header(vertices, triangles);
    append(header.data(), header.size());
  }
  ~PlyStreamWriter() {
    if (file_) {
      std::fclose(file_);
      std::remove(tmp_.c_str());
    }
  }
  void vertex(double x, double y, double z) {
    float p[3] = {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)};
    append(p, 12);
  }
  void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    char record[13];
    record[0] = 3;
    std::uint32_t t[3] = {a, b, c};
    std::memcpy(record + 1, t, 12);
    append(record, 13);
  }
  void commit() {
    flush();
    bool ok = std::fclose(file_) == 0;
    file_ = nullptr;
    if (!ok) throw IoError(path_ + ": write failed (disk full?)");
    if (std::rename(tmp_.c_str(), path_.c_str()) != 0) throw IoError(path_ + ": cannot rename " + tmp_);
  }

 private:
  static constexpr std::size_t kBuffer = 8 << 20;
  void append(const void* data, std::size_t n) {
    if (buffer_.size() + n > kBuffer) flush();
    auto* p = static_cast<const char*>(data);
    buffer_.insert(buffer_.end(), p, p + n);
  }
  void flush() {
    if (!buffer_.empty() && std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size())
      throw IoError(path_ + ": write failed (disk full?)");
    buffer_.clear();
  }
  std::string path_, tmp_;
  std::FILE* file_ = nullptr;
  std::vector<char> buffer_;
};

constexpr std::uint64_t kMaxVertices = 0xFFFFFFF0ull;

GenerateResult terrain(const GenerateParams& p, const std::string& path) {
  // (cols x rows) cells, two triangles each; cells close to square.
  auto half = static_cast<double>(p.triangles) / 2.0;
  auto cols = static_cast<std::uint64_t>(std::ceil(std::sqrt(half)));
  auto rows = static_cast<std::uint64_t>(std::ceil(half / static_cast<double>(cols)));
  std::uint64_t W = cols + 1, H = rows + 1;
  if (W * H > kMaxVertices) throw InvalidInput("too many triangles for 32-bit vertex ids");
  GenerateResult result{W * H, 2 * cols * rows};
  PlyStreamWriter out(path, result.vertices, result.triangles);
  double scale = 1.0 / static_cast<double>(std::max(cols, rows));
  int octaves = std::clamp(static_cast<int>(std::log2(static_cast<double>(std::max(cols, rows)))), 4, 12);
  for (std::uint64_t j = 0; j < H; ++j) {
    for (std::uint64_t i = 0; i < W; ++i) {
      double x = static_cast<double>(i) * scale, y = static_cast<double>(j) * scale;
      double z = 0.25 * fbm(x * 4, y * 4, 0.5, p.seed, octaves);
      out.vertex(x, y, z);
    }
    if (p.progress && j % 256 == 0) p.progress(0.5 * static_cast<double>(j) / static_cast<double>(H));
  }
  for (std::uint64_t r = 0; r < rows; ++r) {
    for (std::uint64_t c = 0; c < cols; ++c) {
      auto a = static_cast<std::uint32_t>(r * W + c), b = a + 1,
           d = static_cast<std::uint32_t>((r + 1) * W + c), e = d + 1;
      out.triangle(a, b, e);
      out.triangle(a, e, d);
    }
    if (p.progress && r % 256 == 0) p.progress(0.5 + 0.5 * static_cast<double>(r) / static_cast<double>(rows));
  }
  out.commit();
  return result;
}

GenerateResult sphere(const GenerateParams& p, const std::string& path) {
  // rings+1 latitude bands (poles included), segments around: 2*segments*rings triangles.
  auto rings = static_cast<std::uint64_t>(std::ceil(std::sqrt(static_cast<double>(p.triangles) / 4.0)));
  rings = std::max<std::uint64_t>(rings, 2);
  std::uint64_t segments = std::max<std::uint64_t>(
      3, static_cast<std::uint64_t>(std::ceil(static_cast<double>(p.triangles) / (2.0 * rings))));
  std::uint64_t V = 2 + (rings - 1) * segments;
  if (V > kMaxVertices) throw InvalidInput("too many triangles for 32-bit vertex ids");
  GenerateResult result{V, 2 * segments * (rings - 1)};
  PlyStreamWriter out(path, result.vertices, result.triangles);
  int octaves = std::clamp(static_cast<int>(std::log2(static_cast<double>(segments))), 4, 12);
  auto radius = [&](double x, double y, double z) {
    return 1.0 + 0.15 * fbm(x * 2 + 3, y * 2 + 3, z * 2 + 3, p.seed, octaves);
  };
  auto emit = [&](double theta, double phi) {
    double x = std::sin(theta) * std::cos(phi), y = std::sin(theta) * std::sin(phi), z = std::cos(theta);
    double r = radius(x, y, z);
    out.vertex(r * x, r * y, r * z);
  };
  emit(0, 0);  // north pole: vertex 0
  for (std::uint64_t k = 1; k < rings; ++k) {
    double theta = std::numbers::pi * static_cast<double>(k) / static_cast<double>(rings);
    for (std::uint64_t s = 0; s < segments; ++s)
      emit(theta, 2 * std::numbers::pi * static_cast<double>(s) / static_cast<double>(segments));
    if (p.progress && k % 64 == 0) p.progress(0.5 * static_cast<double>(k) / static_cast<double>(rings));
  }
  emit(std::numbers::pi, 0);  // south pole: vertex V-1
  auto ring_vertex = [&](std::uint64_t k, std::uint64_t s) {
    return static_cast<std::uint32_t>(1 + (k - 1) * segments + (s % segments));
  };
  auto south = static_cast<std::uint32_t>(V - 1);
  // Outward CCW: looking from outside, theta grows "down" and phi grows "right".
  for (std::uint64_t s = 0; s < segments; ++s) out.triangle(0, ring_vertex(1, s), ring_vertex(1, s + 1));
  for (std::uint64_t k = 1; k + 1 < rings; ++k) {
    for (std::uint64_t s = 0; s < segments; ++s) {
      std::uint32_t a = ring_vertex(k, s), b = ring_vertex(k, s + 1), c = ring_vertex(k + 1, s),
                    d = ring_vertex(k + 1, s + 1);
      out.triangle(a, c, d);
      out.triangle(a, d, b);
    }
    if (p.progress && k % 64 == 0) p.progress(0.5 + 0.5 * static_cast<double>(k) / static_cast<double>(rings));
  }
  for (std::uint64_t s = 0; s < segments; ++s)
    out.triangle(south, ring_vertex(rings - 1, s + 1), ring_vertex(rings - 1, s));
  out.commit();
  return result;
}

}  // namespace

GenerateResult generate_mesh(const GenerateParams& params, const std::string& path) {
  if (params.triangles < 2) throw InvalidInput("--triangles must be at least 2");
  return params.shape == Shape::Terrain ? terrain(params, path) : sphere(params, path);
}

}  // namespace meshflow::mesh
