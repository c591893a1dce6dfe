#include "engine/node_choice.h"

#include <gtest/gtest.h>

namespace meshflow::engine {
namespace {

TEST(ChooseNode, PrefersTheLeastLoadedNode) {
  EXPECT_EQ(choose_node({{.url = "a", .active_steps = 2, .bandwidth_mbps = 100},
                         {.url = "b", .active_steps = 0, .bandwidth_mbps = 1}}),
            "b");
}

TEST(ChooseNode, CountsThisJobsPlannedStepsAsLoad) {
  EXPECT_EQ(choose_node({{.url = "a", .planned_steps = 1, .bandwidth_mbps = 100},
                         {.url = "b", .planned_steps = 0, .bandwidth_mbps = 5}}),
            "b");
  EXPECT_EQ(choose_node({{.url = "a", .active_steps = 1, .planned_steps = 0},
                         {.url = "b", .active_steps = 0, .planned_steps = 2}}),
            "a");
}

TEST(ChooseNode, BreaksTiesByMeasuredBandwidth) {
  EXPECT_EQ(choose_node({{.url = "slow", .bandwidth_mbps = 4.8},
                         {.url = "fast", .bandwidth_mbps = 940},
                         {.url = "mid", .bandwidth_mbps = 100}}),
            "fast");
}

TEST(ChooseNode, TriesAnUnmeasuredNodeSoItGetsMeasured) {
  EXPECT_EQ(choose_node({{.url = "known", .bandwidth_mbps = 940}, {.url = "new", .bandwidth_mbps = 0}}), "new");
}

TEST(ChooseNode, AnswersNothingWithoutCandidates) { EXPECT_FALSE(choose_node({}).has_value()); }

TEST(UpdatedBandwidth, IgnoresTransfersTooSmallToMeasure) {
  EXPECT_EQ(updated_bandwidth(12.5, kMinMeasuredBytes - 1, 1), 12.5);
}

TEST(UpdatedBandwidth, TakesTheFirstTransferThenAveragesWithTheNewest) {
  // 625000 bytes in 1000 ms = 5 Mbit/s.
  double first = updated_bandwidth(0, 625'000, 1000);
  EXPECT_DOUBLE_EQ(first, 5.0);
  double second = updated_bandwidth(first, 625'000, 500);  // 10 Mbit/s
  EXPECT_DOUBLE_EQ(second, 7.5);
}

}  // namespace
}  // namespace meshflow::engine
