#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "sparql/protocol.h"

namespace meshflow::sparql {
namespace {

using repository::QueryResult;
using repository::Term;

TEST(Accept, QWeightsDecide) {
  EXPECT_EQ(choose_format("application/sparql-results+xml;q=0.5, application/sparql-results+json", false),
            Format::Json);
  EXPECT_EQ(choose_format("application/sparql-results+json;q=0.2, application/sparql-results+xml", false),
            Format::Xml);
  EXPECT_EQ(choose_format("text/csv", false), Format::Csv);
  EXPECT_EQ(choose_format("text/tab-separated-values", false), Format::Tsv);
  EXPECT_EQ(choose_format("", false), Format::Json);
  EXPECT_EQ(choose_format("*/*", true), Format::Turtle);
  EXPECT_EQ(choose_format("application/rdf+xml, text/turtle;q=0.5", true), Format::RdfXml);
  EXPECT_EQ(choose_format("image/png", false), std::nullopt);
  EXPECT_EQ(choose_format("text/csv;q=0", false), std::nullopt);
  // SPARQLWrapper's XML request.
  EXPECT_EQ(choose_format("application/sparql-results+xml", false), Format::Xml);
}

TEST(Accept, MalformedPartsAreSkipped) {
  EXPECT_EQ(parse_accept(",,;q=,garbage, text/csv;q=abc").size(), 1u);
  EXPECT_EQ(parse_accept("text/csv;q=abc")[0].q, 0.0);
  EXPECT_TRUE(parse_accept("").empty());
}

QueryResult sample() {
  QueryResult r;
  r.variables = {"a", "b"};
  r.rows.push_back({Term{Term::Kind::Uri, "http://x/1", "", ""},
                    Term{Term::Kind::Literal, "say \"hi\", ok", "", "en"}});
  r.rows.push_back({Term{Term::Kind::Unbound, "", "", ""},
                    Term{Term::Kind::Literal, "3", "http://www.w3.org/2001/XMLSchema#integer", ""}});
  return r;
}

TEST(Writers, JsonIsStandardAndLeavesUnboundOut) {
  auto j = nlohmann::json::parse(write_results(sample(), Format::Json));
  EXPECT_EQ(j["head"]["vars"], (nlohmann::json{"a", "b"}));
  auto& rows = j["results"]["bindings"];
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0]["b"]["xml:lang"], "en");
  EXPECT_FALSE(rows[1].contains("a"));
  EXPECT_EQ(rows[1]["b"]["datatype"], "http://www.w3.org/2001/XMLSchema#integer");
  QueryResult ask;
  ask.kind = QueryResult::Kind::Boolean;
  ask.boolean = true;
  EXPECT_EQ(nlohmann::json::parse(write_results(ask, Format::Json))["boolean"], true);
}

TEST(Writers, CsvTsvXml) {
  auto csv = write_results(sample(), Format::Csv);
  EXPECT_EQ(csv, "a,b\r\nhttp://x/1,\"say \"\"hi\"\", ok\"\r\n,3\r\n");
  auto tsv = write_results(sample(), Format::Tsv);
  EXPECT_EQ(tsv, "?a\t?b\n<http://x/1>\t\"say \\\"hi\\\", ok\"@en\n\t\"3\"^^<http://www.w3.org/2001/XMLSchema#integer>\n");
  auto xml = write_results(sample(), Format::Xml);
  EXPECT_NE(xml.find("<literal xml:lang=\"en\">say &quot;hi&quot;, ok</literal>"), std::string::npos);
}

TEST(Updates, AreRecognised) {
  EXPECT_TRUE(is_update("INSERT DATA { <a> <b> <c> }"));
  EXPECT_TRUE(is_update("PREFIX x: <http://x/>\n# c\n delete where { ?s ?p ?o }"));
  EXPECT_TRUE(is_update("BASE <http://x/> LOAD <http://y>"));
  EXPECT_FALSE(is_update("PREFIX x: <http://x/> SELECT * WHERE { ?s ?p ?o }"));
  EXPECT_FALSE(is_update("ASK {}"));
  EXPECT_FALSE(is_update(""));
}

}  // namespace
}  // namespace meshflow::sparql
