#include "engine/executor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <deque>

#include "engine/in_process_node.h"
#include "engine/workflow_parser.h"
#include "mesh/errors.h"
#include "mesh/measures.h"
#include "mesh/mesh_io.h"
#include "tests/support/meshes.h"

namespace meshflow::engine {
namespace {

// A node that records what ran and answers analyses from a script.
class ScriptedNode : public NodeClient {
 public:
  std::vector<std::string> log;
  std::map<std::string, std::deque<double>> answers;
  StepReport run_atomic(const std::string& op, const services::Params&) override {
    log.push_back(op);
    return {.operation = op};
  }
  // What the executor said may still run, before each step.
  std::vector<std::vector<std::string>> later;
  void expect_later(const std::vector<std::string>& ops) override { later.push_back(ops); }
  StepReport run_analysis(const std::string& op) override {
    auto& queue = answers[op];
    double value = queue.empty() ? 0 : queue.front();
    if (!queue.empty()) queue.pop_front();
    log.push_back(op + "=" + std::to_string(static_cast<int>(value)));
    return {.operation = op, .is_analysis = true, .value = value};
  }
};

void run(const std::string& xml, ScriptedNode& node, int max_loop = 100) {
  Workflow w = parse_workflow(xml, "w.xml");
  ValidatedWorkflow v = validate_workflow(w, "w.xml", services::operation_specs());
  execute(v, node, {.max_loop_iterations = max_loop});
}

const char* kNested = R"(<workflow><body>
  <atomic><name>AddNoise</name></atomic>
  <while><condition><analysis><name>NumberOfBoundaryLoops</name><operator>GT</operator><value>0</value></analysis></condition>
    <body>
      <if><condition><analysis><name>NumberOfComponents</name><operator>GT</operator><value>1</value></analysis></condition>
        <body><atomic><name>RemoveSmallestComponents</name></atomic></body>
        <else><atomic><name>FillHoles</name></atomic></else></if>
    </body></while>
  <atomic><name>LaplacianSmoothing</name></atomic>
</body></workflow>)";

TEST(Executor, RunsTheActiveTaskListThroughNestedIfAndWhile) {
  ScriptedNode node;
  node.answers["NumberOfBoundaryLoops"] = {2, 1, 0};
  node.answers["NumberOfComponents"] = {3, 1};
  run(kNested, node);
  EXPECT_EQ(node.log, (std::vector<std::string>{
                          "AddNoise", "NumberOfBoundaryLoops=2", "NumberOfComponents=3", "RemoveSmallestComponents",
                          "NumberOfBoundaryLoops=1", "NumberOfComponents=1", "FillHoles",
                          "NumberOfBoundaryLoops=0", "LaplacianSmoothing"}));
}

TEST(Executor, TellsTheNodesWhichOperationsMayStillRun) {
  ScriptedNode node;
  node.answers["NumberOfBoundaryLoops"] = {1, 0};
  node.answers["NumberOfComponents"] = {1};
  run(kNested, node);
  using Ops = std::vector<std::string>;
  ASSERT_EQ(node.log.size(), node.later.size());
  // Before AddNoise: everything after it.
  EXPECT_EQ(node.later[0], (Ops{"NumberOfBoundaryLoops", "NumberOfComponents", "RemoveSmallestComponents",
                                "FillHoles", "LaplacianSmoothing"}));
  // Inside the loop, before FillHoles: the loop may come round again, so its operations count.
  auto fill = std::find(node.log.begin(), node.log.end(), "FillHoles") - node.log.begin();
  EXPECT_EQ(node.later[fill], (Ops{"NumberOfBoundaryLoops", "NumberOfComponents", "RemoveSmallestComponents",
                                   "FillHoles", "LaplacianSmoothing"}));
  // The last step: nothing after it.
  EXPECT_EQ(node.later.back(), Ops{});
}

TEST(Executor, StopsARunawayLoopWithItsLine) {
  ScriptedNode node;
  node.answers["NumberOfBoundaryLoops"] = std::deque<double>(50, 1);
  try {
    run(kNested, node, 5);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("the <while> loop at line 3 ran 5 times"), std::string::npos) << e.what();
  }
}

TEST(Executor, InProcessRepairOfTheOgreLeavesOneClosedPiece) {
  const char* repair = R"(<workflow><body>
    <if><condition><analysis><name>NumberOfComponents</name><operator>GT</operator><value>1</value></analysis></condition>
      <body><atomic><name>RemoveSmallestComponents</name></atomic></body></if>
    <while><condition><analysis><name>NumberOfBoundaryLoops</name><operator>GT</operator><value>0</value></analysis></condition>
      <body><atomic><name>FillHoles</name></atomic></body></while>
    <atomic><name>LaplacianSmoothing</name><parameters><parameter>1</parameter></parameters></atomic>
    <atomic><name>RemoveDegenerateTriangles</name></atomic>
  </body></workflow>)";
  Workflow w = parse_workflow(repair, "repair.xml");
  ValidatedWorkflow v = validate_workflow(w, "repair.xml", services::operation_specs());
  InProcessNode node(mesh::read_mesh(testing::shared_meshes() + "/real/ogre.obj"));
  execute(v, node);
  auto m = mesh::compute_measures(node.current());
  EXPECT_EQ(m.components, 1u);
  EXPECT_EQ(m.boundary_loops, 0u);
  EXPECT_EQ(m.degenerate_triangles, 0u);
}

}  // namespace
}  // namespace meshflow::engine
