// libFuzzer target: the SPARQL endpoint's own parsers of outside input, the Accept header
// (q-weighted media ranges) and the update check of a query text, plus the result writers on
// arbitrary term text. None may crash, hang or read out of bounds.
#include <cstdint>
#include <string>

#include "sparql/protocol.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace meshflow;
  std::string text(reinterpret_cast<const char*>(data), size);
  sparql::parse_accept(text);
  sparql::choose_format(text, false);
  sparql::choose_format(text, true);
  sparql::is_update(text);
  repository::QueryResult r;
  r.variables = {text};
  r.rows.push_back({repository::Term{repository::Term::Kind::Literal, text, text, ""}});
  for (auto f : {sparql::Format::Json, sparql::Format::Xml, sparql::Format::Csv, sparql::Format::Tsv})
    sparql::write_results(r, f);
  return 0;
}
