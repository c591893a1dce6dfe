// libFuzzer target: the .mfc correction decoder on arbitrary bytes, applied to a small base
// mesh. It may refuse any input (InvalidInput) but must never crash or allocate absurdly.
#include <cstdint>
#include <span>

#include "mesh/errors.h"
#include "protocol/correction.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace meshflow;
  static const mesh::Mesh base = [] {
    mesh::Mesh m;
    for (int i = 0; i < 8; ++i) m.positions.push_back({float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1)});
    m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                   {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    return m;
  }();
  try {
    protocol::decode_correction(base, {data, size});
  } catch (const InvalidInput&) {
  }
  return 0;
}
