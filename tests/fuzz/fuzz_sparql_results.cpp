// libFuzzer target: the Virtuoso backend's reader of SPARQL JSON results (and of a query's form
// keyword). Arbitrary bytes must give a QueryResult or a ParseError/LimitExceeded, never a crash.
#include <cstdint>
#include <string>

#include "mesh/errors.h"
#include "repository/virtuoso_store.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace meshflow;
  std::string text(reinterpret_cast<const char*>(data), size);
  repository::query_form(text);
  try {
    repository::parse_sparql_json(text, 1000);
  } catch (const InvalidInput&) {
  } catch (const LimitExceeded&) {
  }
  return 0;
}
