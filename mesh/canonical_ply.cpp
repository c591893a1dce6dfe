#include "mesh/canonical_ply.h"

#include <openssl/evp.h>

#include <bit>
#include <cstring>

#include "mesh/errors.h"

namespace meshflow::mesh {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the canonical PLY writer assumes a little-endian host");

constexpr std::size_t kVertexBytes = 12;
constexpr std::size_t kTriangleBytes = 13;
constexpr std::size_t kChunkElements = 1 << 14;

// Calls sink(data, size) with the canonical bytes, in chunks.
template <typename Sink>
void emit_canonical(const Mesh& mesh, Sink&& sink) {
  std::string header = canonical_ply_header(mesh.positions.size(), mesh.triangles.size());
  sink(header.data(), header.size());
  // Positions are already packed float32 triples: write them straight.
  static_assert(sizeof(Point) == kVertexBytes);
  if (!mesh.positions.empty()) sink(mesh.positions.data(), mesh.positions.size() * kVertexBytes);
  std::vector<std::uint8_t> buffer(kChunkElements * kTriangleBytes);
  std::size_t used = 0;
  for (const Triangle& t : mesh.triangles) {
    std::uint8_t* out = buffer.data() + used;
    out[0] = 3;
    std::memcpy(out + 1, t.data(), 12);
    used += kTriangleBytes;
    if (used == buffer.size()) {
      sink(buffer.data(), used);
      used = 0;
    }
  }
  if (used) sink(buffer.data(), used);
}

}  // namespace

std::string canonical_ply_header(std::uint64_t vertex_count, std::uint64_t triangle_count) {
  return "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(vertex_count) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
         std::to_string(triangle_count) + "\nproperty list uchar int vertex_indices\nend_header\n";
}

std::uint64_t canonical_ply_size(std::uint64_t vertex_count, std::uint64_t triangle_count) {
  return canonical_ply_header(vertex_count, triangle_count).size() + vertex_count * kVertexBytes +
         triangle_count * kTriangleBytes;
}

void write_canonical_ply(const Mesh& mesh, std::ostream& out) {
  emit_canonical(mesh, [&](const void* data, std::size_t size) {
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  });
  out.flush();
  if (!out) throw IoError("cannot write the canonical PLY stream");
}

std::vector<std::uint8_t> canonical_ply_bytes(const Mesh& mesh) {
  std::vector<std::uint8_t> bytes;
  bytes.reserve(canonical_ply_size(mesh.positions.size(), mesh.triangles.size()));
  emit_canonical(mesh, [&](const void* data, std::size_t size) {
    auto* p = static_cast<const std::uint8_t*>(data);
    bytes.insert(bytes.end(), p, p + size);
  });
  return bytes;
}

std::string mesh_sha256(const Mesh& mesh) {
  Sha256 hasher;
  emit_canonical(mesh, [&](const void* data, std::size_t size) { hasher.update(data, size); });
  return hasher.hex_digest();
}

Sha256::Sha256() : ctx_(EVP_MD_CTX_new()) {
  if (!ctx_ || EVP_DigestInit_ex(static_cast<EVP_MD_CTX*>(ctx_), EVP_sha256(), nullptr) != 1)
    throw std::runtime_error("cannot initialise SHA-256");
}

Sha256::~Sha256() { EVP_MD_CTX_free(static_cast<EVP_MD_CTX*>(ctx_)); }

void Sha256::update(const void* data, std::size_t size) {
  EVP_DigestUpdate(static_cast<EVP_MD_CTX*>(ctx_), data, size);
}

std::string Sha256::hex_digest() {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestFinal_ex(static_cast<EVP_MD_CTX*>(ctx_), digest, &length);
  static const char* hex = "0123456789abcdef";
  std::string out(length * 2, '0');
  for (unsigned i = 0; i < length; ++i) {
    out[2 * i] = hex[digest[i] >> 4];
    out[2 * i + 1] = hex[digest[i] & 15];
  }
  return out;
}

std::string sha256_hex(const void* data, std::size_t size) {
  Sha256 hasher;
  hasher.update(data, size);
  return hasher.hex_digest();
}

}  // namespace meshflow::mesh
