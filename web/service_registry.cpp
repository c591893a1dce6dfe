#include "web/service_registry.h"

#include <algorithm>
#include <chrono>
#include <fstream>

#include "mesh/errors.h"
#include "protocol/http_client.h"

namespace meshflow::web {

using nlohmann::json;

bool ServiceInfo::offers(const std::string& operation) const {
  if (!service.contains("operations")) return false;
  for (const auto& op : service["operations"])
    if (op.value("name", "") == operation) return true;
  return false;
}

ServiceRegistry::ServiceRegistry(std::filesystem::path file) : file_(std::move(file)) {
  std::ifstream in(file_);
  if (!in) return;
  json saved = json::parse(in, nullptr, false);
  if (!saved.is_array()) return;
  for (const auto& item : saved) {
    ServiceInfo info;
    info.url = item.value("url", "");
    info.service = item.value("service", json::object());
    info.capacity_vertices = item.value("capacity_vertices", std::uint64_t{0});
    info.bandwidth_mbps = item.value("bandwidth_mbps", 0.0);
    if (!info.url.empty()) services_.push_back(std::move(info));
  }
}

ServiceInfo ServiceRegistry::add(const std::string& url) {
  std::string base = url;
  while (!base.empty() && base.back() == '/') base.pop_back();
  if (protocol::url_origin(base).empty()) throw InvalidInput("not an http URL: " + url);
  protocol::HttpOptions http;
  http.timeout = std::chrono::seconds(10);
  protocol::HttpResult res = protocol::http_request("GET", base + "/service.json", {}, http);
  if (!res.ok()) throw IoError("the node at " + base + " did not answer /service.json: " + res.describe());
  json service = json::parse(res.body, nullptr, false);
  if (!service.is_object() || !service.contains("operations") || !service["operations"].is_array())
    throw InvalidInput(base + "/service.json is not a service description (no operations)");
  ServiceInfo info;
  info.url = base;
  info.service = service;
  info.capacity_vertices = service.value("capacity_vertices", std::uint64_t{0});
  // Bandwidth comes from the transfers of jobs (record_transfer), never from this small answer.
  std::lock_guard lock(mutex_);
  auto it = std::find_if(services_.begin(), services_.end(),
                         [&](const ServiceInfo& s) { return s.url == base; });
  if (it != services_.end()) {
    info.active_steps = it->active_steps;
    info.bandwidth_mbps = it->bandwidth_mbps;
    *it = info;
  } else {
    services_.push_back(info);
  }
  save();
  return info;
}

bool ServiceRegistry::remove(const std::string& url) {
  std::lock_guard lock(mutex_);
  auto it = std::remove_if(services_.begin(), services_.end(),
                           [&](const ServiceInfo& s) { return s.url == url; });
  bool removed = it != services_.end();
  services_.erase(it, services_.end());
  if (removed) save();
  return removed;
}

void ServiceRegistry::prune_unreachable() {
  std::vector<std::string> gone;
  for (const auto& s : list()) {
    protocol::HttpOptions http;
    http.timeout = std::chrono::seconds(2);
    http.connect_timeout = std::chrono::seconds(1);
    if (!protocol::http_request("GET", s.url + "/service.json", {}, http).ok()) gone.push_back(s.url);
  }
  for (const auto& url : gone) remove(url);
}

std::vector<ServiceInfo> ServiceRegistry::list() const {
  std::lock_guard lock(mutex_);
  return services_;
}

std::optional<ServiceInfo> ServiceRegistry::find(const std::string& url) const {
  std::lock_guard lock(mutex_);
  for (const auto& s : services_)
    if (s.url == url) return s;
  return std::nullopt;
}

std::vector<engine::NodeCandidate> ServiceRegistry::candidates(const std::string& operation) const {
  std::lock_guard lock(mutex_);
  std::vector<engine::NodeCandidate> out;
  for (const auto& s : services_)
    if (s.offers(operation))
      out.push_back({.url = s.url,
                     .active_steps = s.active_steps,
                     .bandwidth_mbps = s.bandwidth_mbps,
                     .capacity_vertices = s.capacity_vertices});
  return out;
}

std::optional<std::string> ServiceRegistry::choose(const std::string& operation,
                                                   const std::vector<std::string>& exclude) const {
  std::vector<engine::NodeCandidate> offering = candidates(operation);
  std::erase_if(offering, [&](const engine::NodeCandidate& c) {
    return std::find(exclude.begin(), exclude.end(), c.url) != exclude.end();
  });
  return engine::choose_node(offering);
}

void ServiceRegistry::record_transfer(const std::string& url, std::uint64_t bytes, std::int64_t ms) {
  std::lock_guard lock(mutex_);
  for (auto& s : services_)
    if (s.url == url) {
      double updated = engine::updated_bandwidth(s.bandwidth_mbps, bytes, ms);
      if (updated == s.bandwidth_mbps) return;
      s.bandwidth_mbps = updated;
      save();
      return;
    }
}

void ServiceRegistry::adjust_load(const std::string& url, int delta) {
  std::lock_guard lock(mutex_);
  for (auto& s : services_)
    if (s.url == url) s.active_steps += delta;
}

json ServiceRegistry::operations() const {
  std::lock_guard lock(mutex_);
  json out = json::array();
  std::vector<std::string> seen;
  for (const auto& s : services_) {
    for (const auto& op : s.service["operations"]) {
      std::string name = op.value("name", "");
      if (name.empty() || std::find(seen.begin(), seen.end(), name) != seen.end()) continue;
      seen.push_back(name);
      out.push_back(op);
    }
  }
  return out;
}

std::vector<std::string> ServiceRegistry::offered_operations() const {
  std::vector<std::string> names;
  for (const auto& op : operations()) names.push_back(op.value("name", ""));
  return names;
}

void ServiceRegistry::save() const {
  json out = json::array();
  for (const auto& s : services_)
    out.push_back({{"url", s.url},
                   {"service", s.service},
                   {"capacity_vertices", s.capacity_vertices},
                   {"bandwidth_mbps", s.bandwidth_mbps}});
  std::filesystem::path tmp = file_;
  tmp += ".tmp";
  {
    std::ofstream f(tmp);
    f << out.dump(2);
    if (!f) throw IoError("cannot write " + tmp.string());
  }
  std::filesystem::rename(tmp, file_);
}

}  // namespace meshflow::web
