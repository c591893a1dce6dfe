#include "engine/workflow_parser.h"

#include <gtest/gtest.h>

#include <chrono>

#include "engine/validate.h"
#include "mesh/errors.h"
#include "services/operation.h"

namespace meshflow::engine {
namespace {

const char* kRepair = R"(<?xml version="1.0" encoding="utf-8"?>
<workflow>
  <input> http://example.org/bunny.ply </input>
  <body>
    <if><condition><analysis><name>NumberOfComponents</name><operator>GT</operator><value>1</value></analysis></condition>
      <body><atomic><name>RemoveSmallestComponents</name></atomic></body>
      <else><atomic><name>AddNoise</name><parameters><parameter name="seed">4</parameter><parameter name="maxDistance">0.2</parameter></parameters></atomic></else></if>
    <while><condition><analysis><name>IsWatertight</name><operator>NEQ</operator><value>true</value></analysis></condition>
      <body><atomic><name>FillHoles</name></atomic></body></while>
    <atomic><name> LaplacianSmoothing </name><parameters><parameter>3</parameter></parameters></atomic>
  </body>
</workflow>)";

std::string error_of(const std::string& xml) {
  try {
    Workflow w = parse_workflow(xml, "w.xml");
    validate_workflow(w, "w.xml", services::operation_specs());
  } catch (const ParseError& e) {
    return e.what();
  }
  return "";
}

TEST(WorkflowParser, ReadsTheThesisGrammar) {
  Workflow w = parse_workflow(kRepair, "repair.xml");
  ASSERT_TRUE(w.input_url);
  EXPECT_EQ(*w.input_url, "http://example.org/bunny.ply");
  ASSERT_EQ(w.body.size(), 3u);
  EXPECT_EQ(w.body[0].kind, Task::Kind::If);
  EXPECT_EQ(w.body[0].condition.analysis, "NumberOfComponents");
  EXPECT_EQ(w.body[0].condition.op, "GT");
  EXPECT_EQ(w.body[0].else_body.size(), 1u);
  EXPECT_EQ(w.body[1].kind, Task::Kind::While);
  EXPECT_EQ(w.body[2].name, "LaplacianSmoothing");  // trimmed
  EXPECT_EQ(w.body[2].at.line, 10);
  ValidatedWorkflow v = validate_workflow(w, "repair.xml", services::operation_specs());
  EXPECT_EQ(v.params.at(&w.body[2]).at("iterations"), 3);
  EXPECT_EQ(v.params.at(&w.body[0].else_body[0]).at("seed"), 4);
  EXPECT_EQ(v.condition_values.at(&w.body[1]), 1);  // true
  EXPECT_EQ(operations_used(w), (std::vector<std::string>{"NumberOfComponents", "RemoveSmallestComponents",
                                                          "AddNoise", "IsWatertight", "FillHoles",
                                                          "LaplacianSmoothing"}));
}

TEST(WorkflowParser, ErrorsNameLineColumnAndReason) {
  EXPECT_NE(error_of("<workflow><body><atomic><name>Smoth</name></atomic></body></workflow>")
                .find("w.xml:1:25: <atomic> names unknown operation 'Smoth' (known: RemoveSmallestComponents"),
            std::string::npos);
  EXPECT_NE(error_of("<workflow><body>\n<atomic><name>LaplacianSmoothing</name><parameters><parameter>-2</parameter>"
                     "</parameters></atomic></body></workflow>")
                .find("w.xml:2:9: LaplacianSmoothing: parameter iterations=-2: must be >= 1"),
            std::string::npos);
  EXPECT_NE(error_of("<workflow><body><atomic><name>AddNoise</name><parameters><parameter>1</parameter>"
                     "<parameter name=\"seed\">2</parameter></parameters></atomic></body></workflow>")
                .find("all positional or all named"),
            std::string::npos);
  EXPECT_NE(error_of("<workflow><body><if><condition><analysis><name>IsManifold</name><operator>GT</operator>"
                     "</analysis></condition><body/></if></body></workflow>")
                .find("only EQ and NEQ"),
            std::string::npos);
  EXPECT_NE(error_of("<workflow><body><if><condition><analysis><name>NumberOfVertices</name><value>1.5</value>"
                     "</analysis></condition><body/></if></body></workflow>")
                .find("'1.5' is not one"),
            std::string::npos);
  EXPECT_NE(error_of("<workflow><body><atomic><name>NumberOfEdges</name></atomic></body></workflow>")
                .find("is an analysis operation"),
            std::string::npos);
  // Not the grammar: the XSD says so, with a position.
  std::string e = error_of("<workflow><body><loop/></body></workflow>");
  EXPECT_NE(e.find("w.xml:1:"), std::string::npos) << e;
  e = error_of("<workflow><body><atomic><name>Simplify</name></atomic>");
  EXPECT_NE(e.find("w.xml:1:"), std::string::npos) << e;
  EXPECT_NE(error_of("").find("w.xml"), std::string::npos);
}

TEST(WorkflowParser, RefusesExternalEntitiesAndEntityBombs) {
  std::string xxe = "<?xml version=\"1.0\"?>\n<!DOCTYPE workflow [ <!ENTITY x SYSTEM \"file:///etc/passwd\"> ]>\n"
                    "<workflow><body><atomic><name>&x;</name></atomic></body></workflow>";
  std::string e = error_of(xxe);
  EXPECT_NE(e, "");
  EXPECT_EQ(e.find("root:"), std::string::npos);
  std::string bomb = "<?xml version=\"1.0\"?><!DOCTYPE workflow [<!ENTITY a \"aaaaaaaaaa\">";
  std::string previous = "a";
  for (char c = 'b'; c <= 'j'; ++c) {
    bomb += std::string("<!ENTITY ") + c + " \"";
    for (int i = 0; i < 10; ++i) bomb += "&" + previous + ";";
    bomb += "\">";
    previous = std::string(1, c);
  }
  bomb += "]><workflow><body><atomic><name>&j;</name></atomic></body></workflow>";
  auto start = std::chrono::steady_clock::now();
  EXPECT_NE(error_of(bomb), "");
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
}

// Found by tests/fuzz/fuzz_workflow.cpp: Xerces reports an element where the schema allows
// none only at its end, after the handler has seen it; the parser once kept pointers into a
// body that then grew (heap use after free). Such documents are refused, never crash.
TEST(WorkflowParser, RefusesTasksWhereTheSchemaAllowsNoneWithoutCrashing) {
  std::string inside_name = "<workflow><body><if><condition><analysis><name>NumberOfCom\n"
                            "<atomic><name>LaplacianSmoothing</name></atomic>\n"
                            "<atomic><name>FillHoles</name></atomic><atomic><name>FillHoles</name></atomic>"
                            "</name></analysis></condition><body/></if></body></workflow>";
  EXPECT_NE(error_of(inside_name).find("w.xml:"), std::string::npos);
  std::string stray_else = "<workflow><else><atomic><name>FillHoles</name></atomic></else><body/></workflow>";
  EXPECT_NE(error_of(stray_else), "");
  // Deep nesting of valid bodies still reads every task in order.
  std::string xml = "<workflow><body>";
  for (int i = 0; i < 40; ++i)
    xml += "<atomic><name>FillHoles</name></atomic><while><condition><analysis><name>IsManifold</name></analysis>"
           "</condition><body>";
  for (int i = 0; i < 40; ++i) xml += "</body></while>";
  xml += "</body></workflow>";
  Workflow w = parse_workflow(xml, "w.xml");
  const Body* body = &w.body;
  for (int i = 0; i < 40; ++i) {
    ASSERT_EQ(body->size(), 2u);
    EXPECT_EQ((*body)[0].name, "FillHoles");
    body = &(*body)[1].body;
  }
  EXPECT_TRUE(body->empty());
}

}  // namespace
}  // namespace meshflow::engine
