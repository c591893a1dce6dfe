// libFuzzer target: the STL reader on arbitrary bytes. It may refuse any input (ParseError,
// IoError) but must never crash, hang or read out of bounds.
#include <cstdint>
#include <span>

#include "mesh/errors.h"
#include "mesh/input_stream.h"
#include "mesh/readers.h"

namespace {
struct NullSink : meshflow::mesh::MeshSink {
  void vertices(std::span<const meshflow::mesh::Point>) override {}
  void triangles(std::span<const meshflow::mesh::Triangle>) override {}
};
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace meshflow;
  try {
    auto in = mesh::InputStream::from_memory({data, size}, "fuzz.stl");
    NullSink sink;
    mesh::read_stl(in, sink);
  } catch (const InvalidInput&) {
  } catch (const IoError&) {
  }
  return 0;
}
