#include "engine/node_choice.h"

#include <limits>

namespace meshflow::engine {

std::optional<std::string> choose_node(const std::vector<NodeCandidate>& candidates) {
  const NodeCandidate* best = nullptr;
  auto speed = [](const NodeCandidate& c) {
    return c.bandwidth_mbps > 0 ? c.bandwidth_mbps : std::numeric_limits<double>::infinity();
  };
  for (const auto& c : candidates) {
    int load = c.active_steps + c.planned_steps;
    if (!best) {
      best = &c;
      continue;
    }
    int best_load = best->active_steps + best->planned_steps;
    if (load < best_load || (load == best_load && speed(c) > speed(*best))) best = &c;
  }
  if (!best) return std::nullopt;
  return best->url;
}

double updated_bandwidth(double previous_mbps, std::uint64_t bytes, std::int64_t ms) {
  if (bytes < kMinMeasuredBytes) return previous_mbps;
  double mbps = static_cast<double>(bytes) * 8.0 / (static_cast<double>(ms < 1 ? 1 : ms) * 1000.0);
  constexpr double kWeight = 0.5;  // of the newest transfer
  return previous_mbps <= 0 ? mbps : (1 - kWeight) * previous_mbps + kWeight * mbps;
}

}  // namespace meshflow::engine
