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
  auto start = std::chrono::steady_clock::now();
  protocol::HttpOptions http;
  http.timeout = std::chrono::seconds(10);
  protocol::HttpResult res = protocol::http_request("GET", base + "/service.json", {}, http);
  if (!res.ok()) throw IoError("the node at " + base + " did not answer /service.json: " + res.describe());
  double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  json service = json::parse(res.body, nullptr, false);
  if (!service.is_object() || !service.contains("operations") || !service["operations"].is_array())
    throw InvalidInput(base + "/service.json is not a service description (no operations)");
  ServiceInfo info;
  info.url = base;
  info.service = service;
  info.capacity_vertices = service.value("capacity_vertices", std::uint64_t{0});
  // A first, rough bandwidth figure from the size of the description and its round trip;
  // the engine refines its choice by load.
  info.bandwidth_mbps = seconds > 0 ? res.body.size() * 8 / seconds / 1e6 : 0;
  std::lock_guard lock(mutex_);
  auto it = std::find_if(services_.begin(), services_.end(),
                         [&](const ServiceInfo& s) { return s.url == base; });
  if (it != services_.end()) {
    info.active_steps = it->active_steps;
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

std::optional<std::string> ServiceRegistry::choose(const std::string& operation,
                                                   const std::vector<std::string>& exclude) const {
  std::lock_guard lock(mutex_);
  const ServiceInfo* best = nullptr;
  for (const auto& s : services_) {
    if (!s.offers(operation)) continue;
    if (std::find(exclude.begin(), exclude.end(), s.url) != exclude.end()) continue;
    if (!best || s.active_steps < best->active_steps ||
        (s.active_steps == best->active_steps && s.bandwidth_mbps > best->bandwidth_mbps))
      best = &s;
  }
  if (!best) return std::nullopt;
  return best->url;
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
