#include "repository/accounts.h"

#include <sodium.h>
#include <sqlite3.h>

#include "mesh/errors.h"

namespace meshflow::repository {
namespace {

std::string hex(const unsigned char* p, std::size_t n) {
  std::string s(2 * n + 1, '\0');
  sodium_bin2hex(s.data(), s.size(), p, n);
  s.pop_back();
  return s;
}

std::string digest(const std::string& token) {
  unsigned char out[crypto_hash_sha256_BYTES];
  crypto_hash_sha256(out, reinterpret_cast<const unsigned char*>(token.data()), token.size());
  return hex(out, sizeof out);
}

bool valid_name(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  for (unsigned char c : name)
    if (!std::isalnum(c) && c != '_' && c != '-' && c != '.') return false;
  return true;
}

// One prepared statement, finalized on scope exit.
struct Stmt {
  sqlite3_stmt* s = nullptr;
  Stmt(sqlite3* db, const char* sql) {
    if (sqlite3_prepare_v2(db, sql, -1, &s, nullptr) != SQLITE_OK)
      throw IoError(std::string("accounts database: ") + sqlite3_errmsg(db));
  }
  ~Stmt() { sqlite3_finalize(s); }
  Stmt& bind(int i, const std::string& v) {
    sqlite3_bind_text(s, i, v.c_str(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
    return *this;
  }
  bool step() { return sqlite3_step(s) == SQLITE_ROW; }
  std::string text(int i) {
    auto p = sqlite3_column_text(s, i);
    return p ? reinterpret_cast<const char*>(p) : "";
  }
};

}  // namespace

bool valid_role(const std::string& role) {
  return role == "user" || role == "curator" || role == "admin";
}
int role_rank(const std::string& role) {
  return role == "admin" ? 3 : role == "curator" ? 2 : role == "user" ? 1 : 0;
}

struct Accounts::Impl {
  sqlite3* db = nullptr;
  Repository* repo = nullptr;
  std::mutex mutex;
};

Accounts::Accounts(const std::filesystem::path& data_dir, Repository& repo)
    : impl_(std::make_unique<Impl>()) {
  if (sodium_init() < 0) throw IoError("libsodium could not start");
  impl_->repo = &repo;
  auto dir = data_dir / "repository";
  std::filesystem::create_directories(dir);
  auto path = (dir / "accounts.sqlite").string();
  if (sqlite3_open(path.c_str(), &impl_->db) != SQLITE_OK)
    throw IoError("cannot open " + path);
  const char* schema =
      "PRAGMA journal_mode=WAL;"
      "CREATE TABLE IF NOT EXISTS users(name TEXT PRIMARY KEY, role TEXT NOT NULL, hash TEXT NOT NULL);"
      "CREATE TABLE IF NOT EXISTS tokens(digest TEXT PRIMARY KEY, name TEXT NOT NULL);";
  if (sqlite3_exec(impl_->db, schema, nullptr, nullptr, nullptr) != SQLITE_OK)
    throw IoError(std::string("accounts database: ") + sqlite3_errmsg(impl_->db));
}

Accounts::~Accounts() { sqlite3_close(impl_->db); }

Account Accounts::add(const std::string& name, const std::string& password,
                      const std::string& role) {
  if (!valid_name(name))
    throw InvalidInput("a user name has 1 to 64 letters, digits, '_', '-' or '.'");
  if (!valid_role(role)) throw InvalidInput("role must be user, curator or admin, not \"" + role + "\"");
  if (password.size() < 8 || password.size() > 1024)
    throw InvalidInput("a password has 8 to 1024 characters");
  char hash[crypto_pwhash_STRBYTES];
  if (crypto_pwhash_str(hash, password.c_str(), password.size(),
                        crypto_pwhash_OPSLIMIT_INTERACTIVE, crypto_pwhash_MEMLIMIT_INTERACTIVE) != 0)
    throw IoError("out of memory hashing the password");
  {
    std::lock_guard lock(impl_->mutex);
    Stmt insert(impl_->db, "INSERT INTO users(name, role, hash) VALUES(?, ?, ?)");
    insert.bind(1, name).bind(2, role).bind(3, hash);
    if (sqlite3_step(insert.s) != SQLITE_DONE)
      throw InvalidInput("the user name \"" + name + "\" is taken");
  }
  std::string s = std::string(kUserBase) + name;
  impl_->repo->store().add({{s, "http://www.w3.org/1999/02/22-rdf-syntax-ns#type",
                             std::string(kWo) + "User"},
                            {s, std::string(kWo) + "name", name, true, ""},
                            {s, std::string(kWo) + "role", role, true, ""}});
  return {name, role};
}

std::optional<Account> Accounts::find(const std::string& name) {
  std::lock_guard lock(impl_->mutex);
  Stmt q(impl_->db, "SELECT role FROM users WHERE name = ?");
  q.bind(1, name);
  if (!q.step()) return std::nullopt;
  return Account{name, q.text(0)};
}

std::optional<Account> Accounts::verify(const std::string& name, const std::string& password) {
  std::string role, hash;
  {
    std::lock_guard lock(impl_->mutex);
    Stmt q(impl_->db, "SELECT role, hash FROM users WHERE name = ?");
    q.bind(1, name);
    if (!q.step()) return std::nullopt;
    role = q.text(0);
    hash = q.text(1);
  }
  if (crypto_pwhash_str_verify(hash.c_str(), password.c_str(), password.size()) != 0)
    return std::nullopt;
  return Account{name, role};
}

std::string random_hex(std::size_t bytes) {
  std::string raw(bytes, '\0');
  randombytes_buf(raw.data(), bytes);
  return hex(reinterpret_cast<const unsigned char*>(raw.data()), bytes);
}

std::string Accounts::new_token(const std::string& name) {
  std::string token = "mft_" + random_hex(32);
  std::lock_guard lock(impl_->mutex);
  Stmt insert(impl_->db, "INSERT INTO tokens(digest, name) VALUES(?, ?)");
  insert.bind(1, digest(token)).bind(2, name);
  if (sqlite3_step(insert.s) != SQLITE_DONE) throw IoError("cannot store the token");
  return token;
}

std::optional<Account> Accounts::by_token(const std::string& token) {
  std::lock_guard lock(impl_->mutex);
  Stmt q(impl_->db,
         "SELECT users.name, users.role FROM tokens JOIN users ON users.name = tokens.name "
         "WHERE tokens.digest = ?");
  q.bind(1, digest(token));
  if (!q.step()) return std::nullopt;
  return Account{q.text(0), q.text(1)};
}

}  // namespace meshflow::repository
