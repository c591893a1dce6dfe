#pragma once
// Accounts (DESIGN §3): users with a role (user, curator, admin) and API tokens. Each user is
// also an RDF resource (wo:User with name and role); the secrets (Argon2id password hashes
// from libsodium's crypto_pwhash_str, SHA-256 digests of API tokens) live only in
// DATA/repository/accounts.sqlite, never in the triples /sparql can read.

#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "repository/repository.h"

namespace meshflow::repository {

// `bytes` random bytes (libsodium's CSPRNG) as lowercase hex: session ids, tokens.
std::string random_hex(std::size_t bytes);

struct Account {
  std::string name, role;
};

class Accounts {
 public:
  // \throws IoError.
  Accounts(const std::filesystem::path& data_dir, Repository& repo);
  ~Accounts();

  // \throws InvalidInput (bad name or role, password shorter than 8, name taken).
  Account add(const std::string& name, const std::string& password, const std::string& role);
  std::optional<Account> verify(const std::string& name, const std::string& password);
  std::optional<Account> find(const std::string& name);
  std::string new_token(const std::string& name);  // shown once; stored as a digest
  std::optional<Account> by_token(const std::string& token);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

bool valid_role(const std::string& role);
int role_rank(const std::string& role);  // anonymous 0, user 1, curator 2, admin 3

}  // namespace meshflow::repository
