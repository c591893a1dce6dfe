#pragma once
// The SPARQL 1.1 Protocol pieces that do not touch HTTP (DESIGN §7): content negotiation over
// q-weighted Accept lists, the result writers (standard JSON, not rasqal's; XML; CSV; TSV) and
// the refusal of updates.

#include <optional>
#include <string>
#include <vector>

#include "repository/rdf_store.h"

namespace meshflow::sparql {

enum class Format { Json, Xml, Csv, Tsv, Turtle, RdfXml };

struct MediaRange {
  std::string type;  // "application/sparql-results+json", "text/*", "*/*"
  double q = 1.0;
};

// Parses an Accept header ("a/b;q=0.9, c/d"); malformed parts are skipped, never thrown.
std::vector<MediaRange> parse_accept(const std::string& header);
// The best format for a result kind (graph: Turtle / RDF-XML; else JSON / XML / CSV / TSV);
// an empty or wildcard header gives JSON (graph: Turtle); nullopt when nothing offered fits.
std::optional<Format> choose_format(const std::string& accept_header, bool graph);
std::string content_type(Format format);
const char* redland_graph_format(Format format);  // "turtle" or "rdfxml"

// SELECT and ASK results in `format` (JSON, XML, CSV or TSV).
std::string write_results(const repository::QueryResult& result, Format format);

// True when the text is a SPARQL Update request (INSERT, DELETE, LOAD, CLEAR, ...), judged by
// its first keyword after the prologue.
bool is_update(const std::string& text);

}  // namespace meshflow::sparql
