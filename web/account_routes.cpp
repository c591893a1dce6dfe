#include "web/account_routes.h"

#include <httplib.h>
#include <sodium.h>

#include <nlohmann/json.hpp>

#include "mesh/errors.h"
#include "protocol/http_server.h"

namespace meshflow::web {
namespace {

using nlohmann::json;
constexpr const char* kCookie = "meshflow_session";

std::string cookie_value(const httplib::Request& req, const std::string& name) {
  std::string header = req.get_header_value("Cookie");
  std::size_t pos = 0;
  while (pos < header.size()) {
    auto end = header.find(';', pos);
    if (end == std::string::npos) end = header.size();
    auto part = header.substr(pos, end - pos);
    auto b = part.find_first_not_of(' ');
    if (b != std::string::npos) part = part.substr(b);
    if (part.rfind(name + "=", 0) == 0) return part.substr(name.size() + 1);
    pos = end + 1;
  }
  return "";
}

json body_json(const httplib::Request& req) {
  if (req.body.size() > (64 << 10)) throw LimitExceeded("request body bytes", 64 << 10, req.body.size());
  try {
    auto j = json::parse(req.body);
    if (!j.is_object()) throw InvalidInput("the body must be a JSON object");
    return j;
  } catch (const json::exception& e) {  // syntax, or a number out of range
    throw InvalidInput(std::string("the body is not JSON: ") + e.what());
  }
}

std::string field(const json& j, const char* name) {
  if (!j.contains(name) || !j[name].is_string())
    throw InvalidInput(std::string("missing the string field \"") + name + "\"");
  return j[name].get<std::string>();
}

void reply_session(httplib::Response& res, Auth& auth, const repository::Account& account,
                   int status) {
  auto [id, session] = auth.open_session(account);
  res.set_header("Set-Cookie", std::string(kCookie) + "=" + id +
                                   "; HttpOnly; SameSite=Strict; Path=/");
  res.status = status;
  res.set_content(json{{"name", account.name}, {"role", account.role}, {"csrf", session.csrf}}.dump(),
                  "application/json");
}

}  // namespace

std::pair<std::string, Auth::Session> Auth::open_session(const repository::Account& account) {
  Session s{account, repository::random_hex(24)};
  std::string id = repository::random_hex(32);
  std::lock_guard lock(mutex_);
  sessions_[id] = s;
  return {id, s};
}

std::optional<Auth::Session> Auth::session(const httplib::Request& req) {
  auto id = cookie_value(req, kCookie);
  if (id.empty()) return std::nullopt;
  std::lock_guard lock(mutex_);
  auto it = sessions_.find(id);
  if (it == sessions_.end()) return std::nullopt;
  return it->second;
}

void Auth::close_session(const httplib::Request& req) {
  auto id = cookie_value(req, kCookie);
  std::lock_guard lock(mutex_);
  sessions_.erase(id);
}

std::optional<repository::Account> Auth::caller(const httplib::Request& req) {
  std::string header = req.get_header_value("Authorization");
  if (header.rfind("Bearer ", 0) == 0) {
    auto account = accounts_.by_token(header.substr(7));
    if (!account) throw protocol::Unauthorized("unknown API token");
    return account;
  }
  auto s = session(req);
  if (!s) return std::nullopt;
  if (req.method != "GET" && req.method != "HEAD") {
    auto csrf = req.get_header_value("X-CSRF-Token");
    if (csrf.empty() || sodium_memcmp(csrf.data(), s->csrf.data(), s->csrf.size()) != 0 ||
        csrf.size() != s->csrf.size())
      throw protocol::Forbidden("a cookie-authenticated " + req.method +
                                " needs the header X-CSRF-Token of its session");
  }
  return s->account;
}

repository::Account Auth::require(const httplib::Request& req, const std::string& role) {
  auto who = caller(req);
  if (!who) throw protocol::Unauthorized("log in first (POST /api/session) or send an API token");
  if (repository::role_rank(who->role) < repository::role_rank(role))
    throw protocol::Forbidden("this needs the role " + role + "; " + who->name + " is " + who->role);
  return *who;
}

void add_account_routes(HubServer& hub, Auth& auth) {
  auto& server = hub.http();
  server.Post("/api/users", [&auth](const httplib::Request& req, httplib::Response& res) {
    auto j = body_json(req);
    auto account = auth.accounts().add(field(j, "name"), field(j, "password"), "user");
    reply_session(res, auth, account, 201);
  });
  server.Post("/api/session", [&auth](const httplib::Request& req, httplib::Response& res) {
    auto j = body_json(req);
    auto account = auth.accounts().verify(field(j, "name"), field(j, "password"));
    if (!account) throw protocol::Unauthorized("wrong user name or password");
    reply_session(res, auth, *account, 200);
  });
  server.Get("/api/session", [&auth](const httplib::Request& req, httplib::Response& res) {
    auto s = auth.session(req);
    if (!s) throw protocol::Unauthorized("not logged in");
    res.set_content(json{{"name", s->account.name}, {"role", s->account.role}, {"csrf", s->csrf}}.dump(),
                    "application/json");
  });
  server.Delete("/api/session", [&auth](const httplib::Request& req, httplib::Response& res) {
    auth.caller(req);  // the CSRF check
    auth.close_session(req);
    res.set_header("Set-Cookie", std::string(kCookie) + "=; HttpOnly; SameSite=Strict; Path=/; Max-Age=0");
    res.status = 204;
  });
  server.Post("/api/tokens", [&auth](const httplib::Request& req, httplib::Response& res) {
    auto who = auth.require(req, "user");
    res.status = 201;
    res.set_content(json{{"token", auth.accounts().new_token(who.name)}}.dump(), "application/json");
  });
}

}  // namespace meshflow::web
