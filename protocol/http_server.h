#pragma once
// What the hub (web/) and the node (services/) servers share on the wire: one mapping from
// exceptions to HTTP status and a JSON error body {"error": "...", "where": {...}}, and file
// serving with validated Range requests (cpp-httplib 0.11 answers a range past the end with a
// bogus Content-Length; GROUND.md §10).

#include <httplib.h>

#include <exception>
#include <string>

namespace meshflow::protocol {

struct ErrorReply {
  int status = 500;
  std::string body;  // {"error": "...", "where": {...}}
};

// InvalidInput/ParseError -> 400 (ParseError adds where: file, line, column, byte),
// LimitExceeded -> 413, IoError -> 502, NotFound -> 404, Forbidden -> 403, Unauthorized -> 401,
// Unavailable -> 503, anything else -> 500.
ErrorReply error_reply(std::exception_ptr error);

// Writes an error reply with the given status and message.
void reply_error(httplib::Response& res, int status, const std::string& message);

// Exception and error handlers that answer every failure with the JSON error body; nothing
// thrown by a handler escapes to crash the server.
void install_error_handling(httplib::Server& server);

// Serves a file with Content-Length, Accept-Ranges and single-range support; answers 416 for a
// range outside the file and 404 when the file does not exist.
void serve_file(const httplib::Request& req, httplib::Response& res, const std::string& path,
                const std::string& content_type);

// HTTP-flavoured errors for handlers to throw.
class NotFound : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
class Unauthorized : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
class Forbidden : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
class Unavailable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace meshflow::protocol
