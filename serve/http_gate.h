// serve's gate: what every request's head must be before the HTTP library parses it or any handler
// runs. The head (request line and header lines, through the blank line) is screened whole, as
// bytes: a head that breaks a rule gets one 4xx with one line saying why, and its connection is
// closed. The rules refuse what a hostile client or page can send and a page of serve's never
// does: bodies (every parameter travels in the query), ambiguous lengths (request smuggling),
// bytes that are not text, header floods, and Host names that are not this server's (DNS
// rebinding). Pure functions: the router's fuzzer and the unit tests call them directly.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace fetchscope::serve {

/// The most bytes a request's head may have (request line and headers): 431 past it.
inline constexpr size_t kMaxHeadBytes = 16384;
/// The most header lines a request may have: 431 past it.
inline constexpr size_t kMaxHeaderLines = 100;
/// The most bytes of a request target (path and query): 414 past it.
inline constexpr size_t kMaxTargetBytes = 8192;
/// A request's whole head must arrive within this many seconds of its first wait (408 after):
/// a client that drips its header a byte at a time is dropped, whatever its pace.
inline constexpr double kHeadDeadlineSeconds = 10;

/// Which Host headers name this server.
struct HostRules {
  /// Names accepted besides IP literals (compared without case): "localhost", the --host given
  /// when it is a name, this machine's host name.
  std::vector<std::string> names;
};

/// Why a head is refused: an HTTP status (0: accepted) and one line.
struct Refusal {
  int status = 0;
  std::string message;
  explicit operator bool() const { return status != 0; }
};

/// Screens one complete request head (it ends with the blank line's CR LF CR LF). Refuses (4xx):
/// a line not ended by CR LF, a request line not of METHOD SP /TARGET SP HTTP/1.x, a target with
/// a byte outside printable ASCII or a malformed or control-byte percent escape (%00 among them),
/// a query pair with a second '=', a header line that is not NAME: VALUE in printable text,
/// more than kMaxHeaderLines header lines, a missing or repeated Host or one that does not name
/// this server (HostAllowed), a repeated or non-numeric Content-Length, Content-Length with
/// Transfer-Encoding, and any request body (Content-Length above 0, or Transfer-Encoding: 413).
Refusal ScreenHead(std::string_view head, const HostRules& rules);

/// Whether a Host header's value names this server: an IPv4 or bracketed IPv6 literal, or one of
/// `rules.names`, with an optional port. The port is not compared: ssh -L may forward another
/// local port to serve's, and only a name can be rebound to another address.
bool HostAllowed(std::string_view host, const HostRules& rules);

/// `bytes` as text that is safe to quote in a message (and in JSON): valid UTF-8 is kept, every
/// other byte and every control byte is written \xNN; at most `max_bytes` of the input, cut on a
/// character's boundary, then "...".
std::string Printable(std::string_view bytes, size_t max_bytes = 80);

}  // namespace fetchscope::serve
