#pragma once
// Accounts on the hub (DESIGN §3): sign-up, cookie sessions with a CSRF token, API tokens, and
// the caller of a request (anonymous, or an account with its role).

#include <map>
#include <mutex>
#include <optional>
#include <string>

#include "repository/accounts.h"
#include "web/hub_server.h"

namespace httplib {
struct Request;
}

namespace meshflow::web {

class Auth {
 public:
  explicit Auth(repository::Accounts& accounts) : accounts_(accounts) {}
  // Who sent the request: `Authorization: Bearer TOKEN` or the session cookie. A cookie on a
  // POST/PUT/DELETE must come with `X-CSRF-Token`. \throws protocol::Forbidden, Unauthorized.
  std::optional<repository::Account> caller(const httplib::Request& req);
  // caller() with at least `role`. \throws Unauthorized (anonymous), Forbidden (too low).
  repository::Account require(const httplib::Request& req, const std::string& role);

  struct Session {
    repository::Account account;
    std::string csrf;
  };
  std::pair<std::string, Session> open_session(const repository::Account& account);
  std::optional<Session> session(const httplib::Request& req);
  void close_session(const httplib::Request& req);
  repository::Accounts& accounts() { return accounts_; }

 private:
  repository::Accounts& accounts_;
  std::mutex mutex_;
  std::map<std::string, Session> sessions_;  // in memory: a restart logs everyone out
};

void add_account_routes(HubServer& hub, Auth& auth);

}  // namespace meshflow::web
