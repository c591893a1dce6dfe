#pragma once
// Output files of the mesh writers (mesh_io.cpp, canonical_copy.cpp): optional gzip or zstd
// compression chosen by a trailing .gz or .zst, written to `<path>.tmp` and renamed by commit().
// Internal to mesh/: the public entry points are write_mesh() and copy_canonical_ply().

#include <zlib.h>
#include <zstd.h>

#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "mesh/mesh_io.h"

namespace meshflow::mesh {

// The lowercase extension of `path` (".ply", ".zst"...), "" when it has none.
std::string lower_extension(const std::string& path);

// The path without a trailing .gz/.zst, and which compression that suffix asks for.
std::pair<std::string, Compression> strip_compression(const std::string& path);

class OutputFile {
 public:
  // Creates `<path>.tmp`. \throws IoError when it cannot be created.
  OutputFile(std::string path, Compression compression);
  // Without commit(): the .tmp file is removed.
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  // The same bytes give the same file whatever the sizes of the pieces they come in.
  // \throws IoError when writing fails.
  void write(const void* data, std::size_t size);
  // Finishes the compressed stream, closes and renames `<path>.tmp` to `path`. \throws IoError.
  void commit();

 private:
  void raw(const void* data, std::size_t size);
  void deflate_all(int flush);
  std::size_t zstd_step(ZSTD_inBuffer& in, ZSTD_EndDirective mode);

  std::string path_, tmp_;
  Compression compression_;
  std::FILE* file_ = nullptr;
  z_stream z_{};
  ZSTD_CCtx* zstd_ = nullptr;
  std::vector<char> out_;
};

}  // namespace meshflow::mesh
