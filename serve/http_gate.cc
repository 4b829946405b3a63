#include "serve/http_gate.h"

#include <arpa/inet.h>

#include <cctype>
#include <cstdio>

namespace fetchscope::serve {
namespace {

bool IsTokenChar(unsigned char c) {  // RFC 9110's tchar
  return std::isalnum(c) ||
         std::string_view("!#$%&'*+-.^_`|~").find(static_cast<char>(c)) != std::string_view::npos;
}

int HexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::string Lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

Refusal Refuse(int status, std::string message) { return Refusal{status, std::move(message)}; }

// The request target: printable ASCII, well-formed percent escapes that decode to no control
// byte, and at most one '=' in each query pair.
Refusal ScreenTarget(std::string_view target) {
  if (target.size() > kMaxTargetBytes) {
    return Refuse(414, "the URL has " + std::to_string(target.size()) + " bytes: at most " +
                           std::to_string(kMaxTargetBytes) + " are accepted");
  }
  if (target.empty() || target.front() != '/') {
    return Refuse(400, "the request target '" + Printable(target) +
                           "' does not start with '/': only a path and query are accepted");
  }
  for (size_t i = 0; i < target.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(target[i]);
    if (c <= 0x20 || c >= 0x7f) {
      return Refuse(
          400, "the URL holds the byte \\x" + [c] {
            char hex[3];
            std::snprintf(hex, sizeof(hex), "%02x", c);
            return std::string(hex);
          }() + " unencoded: a URL is printable ASCII (percent-encode the rest)");
    }
    if (c != '%') continue;
    const int hi = i + 2 < target.size() ? HexValue(target[i + 1]) : -1;
    const int lo = i + 2 < target.size() ? HexValue(target[i + 2]) : -1;
    if (hi < 0 || lo < 0) {
      return Refuse(400, "the URL holds a malformed percent escape '" +
                             Printable(target.substr(i, 3)) +
                             "': '%' must be followed by two "
                             "hex digits (%25 for '%' itself)");
    }
    const int byte = hi * 16 + lo;
    if (byte < 0x20 || byte == 0x7f) {
      return Refuse(400, "the URL holds the encoded control byte '" +
                             std::string(target.substr(i, 3)) +
                             "': paths and parameter values are text, without control bytes");
    }
    i += 2;
  }
  const size_t q = target.find('?');
  if (q == std::string_view::npos) return {};
  std::string_view query = target.substr(q + 1);
  while (!query.empty()) {
    const size_t amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    const size_t eq = pair.find('=');
    if (eq != std::string_view::npos && pair.find('=', eq + 1) != std::string_view::npos) {
      return Refuse(400, "the query pair '" + Printable(pair) +
                             "' has a second '=': encode a '=' inside a value as %3D");
    }
    if (amp == std::string_view::npos) break;
    query.remove_prefix(amp + 1);
  }
  return {};
}

// One header line's name and value, or a refusal.
Refusal SplitHeader(std::string_view line, std::string_view* name, std::string_view* value) {
  if (!line.empty() && (line.front() == ' ' || line.front() == '\t')) {
    return Refuse(400, "a header line starts with white space (obsolete line folding is refused)");
  }
  const size_t colon = line.find(':');
  if (colon == std::string_view::npos || colon == 0) {
    return Refuse(400, "the header line '" + Printable(line) + "' is not NAME: VALUE");
  }
  *name = line.substr(0, colon);
  for (char c : *name) {
    if (!IsTokenChar(static_cast<unsigned char>(c))) {
      return Refuse(400, "the header name '" + Printable(*name) +
                             "' holds a character a header name cannot have");
    }
  }
  *value = Trim(line.substr(colon + 1));
  for (char ch : *value) {
    const unsigned char c = static_cast<unsigned char>(ch);
    if ((c < 0x20 && c != '\t') || c == 0x7f) {
      return Refuse(400, "the header " + std::string(*name) +
                             " holds a control byte: header values are text");
    }
  }
  return {};
}

// METHOD SP TARGET SP HTTP/1.x
Refusal ScreenRequestLine(std::string_view request_line) {
  const size_t sp1 = request_line.find(' ');
  const size_t sp2 =
      sp1 == std::string_view::npos ? std::string_view::npos : request_line.find(' ', sp1 + 1);
  if (sp1 == std::string_view::npos || sp2 == std::string_view::npos ||
      request_line.find(' ', sp2 + 1) != std::string_view::npos) {
    return Refuse(
        400, "the request line '" + Printable(request_line) + "' is not METHOD /TARGET HTTP/1.1");
  }
  const std::string_view method = request_line.substr(0, sp1);
  const std::string_view version = request_line.substr(sp2 + 1);
  if (method.empty()) return Refuse(400, "the request line has no method");
  for (char c : method) {
    if (!IsTokenChar(static_cast<unsigned char>(c))) {
      return Refuse(400, "the method '" + Printable(method) + "' is not a method name");
    }
  }
  if (version != "HTTP/1.1" && version != "HTTP/1.0") {
    return Refuse(version.rfind("HTTP/", 0) == 0 ? 505 : 400,
                  "the protocol '" + Printable(version) + "' is not HTTP/1.1 or HTTP/1.0");
  }
  if (Refusal r = ScreenTarget(request_line.substr(sp1 + 1, sp2 - sp1 - 1))) return r;
  return {};
}

// The header lines (after the request line): each NAME: VALUE in text, one Host naming this
// server, an unambiguous length, and no body.
Refusal ScreenHeaders(const std::vector<std::string_view>& lines, const HostRules& rules) {
  int hosts = 0;
  int lengths = 0;
  bool chunked = false;
  std::string_view host;
  std::string_view length;
  for (size_t i = 1; i < lines.size(); ++i) {
    std::string_view name;
    std::string_view value;
    if (Refusal r = SplitHeader(lines[i], &name, &value)) return r;
    const std::string lower = Lower(name);
    if (lower == "host") {
      ++hosts;
      host = value;
    } else if (lower == "content-length") {
      ++lengths;
      length = value;
    } else if (lower == "transfer-encoding") {
      chunked = true;
    }
  }
  if (hosts != 1) {
    return Refuse(400, hosts == 0 ? "the request has no Host header"
                                  : "the request has " + std::to_string(hosts) + " Host headers");
  }
  if (!HostAllowed(host, rules)) {
    std::string names;
    for (const std::string& n : rules.names) names += ", " + n;
    return Refuse(403, "Host '" + Printable(host) +
                           "' does not name this server: only an IP address" + names +
                           " (a page under another name, as in DNS rebinding, is refused)");
  }
  if (lengths > 1) {
    return Refuse(400, "the request has " + std::to_string(lengths) +
                           " Content-Length headers: at most one is accepted");
  }
  if (lengths == 1 && chunked) {
    return Refuse(400, "the request has both Content-Length and Transfer-Encoding: refused");
  }
  if (lengths == 1) {
    bool digits = !length.empty() && length.size() <= 18;
    for (char c : length) digits = digits && c >= '0' && c <= '9';
    if (!digits) {
      return Refuse(400, "Content-Length '" + Printable(length) + "' is not a number of bytes");
    }
    if (length.find_first_not_of('0') != std::string_view::npos) {
      return Refuse(413, "a request body of " + std::string(length) +
                             " bytes: serve's API takes no body (every parameter goes in the "
                             "URL's query)");
    }
  }
  if (chunked) {
    return Refuse(413,
                  "a request body sent with Transfer-Encoding: serve's API takes no body "
                  "(every parameter goes in the URL's query)");
  }
  return {};
}

}  // namespace

std::string Printable(std::string_view bytes, size_t max_bytes) {
  std::string out;
  size_t i = 0;
  auto escape = [&out](unsigned char c) {
    char hex[5];
    std::snprintf(hex, sizeof(hex), "\\x%02x", c);
    out += hex;
  };
  while (i < bytes.size()) {
    const unsigned char c = static_cast<unsigned char>(bytes[i]);
    // the length of a valid UTF-8 sequence starting here (0: not one)
    size_t n = 0;
    if (c >= 0x20 && c < 0x7f) {
      n = 1;
    } else if (c >= 0xc2 && c <= 0xf4) {
      const size_t want = c < 0xe0 ? 2 : c < 0xf0 ? 3 : 4;
      bool ok = i + want <= bytes.size();
      for (size_t k = 1; ok && k < want; ++k) {
        ok = (static_cast<unsigned char>(bytes[i + k]) & 0xc0) == 0x80;
      }
      if (ok && want >= 3) {  // no overlong forms, surrogates or code points past U+10FFFF
        const unsigned char c1 = static_cast<unsigned char>(bytes[i + 1]);
        if ((c == 0xe0 && c1 < 0xa0) || (c == 0xed && c1 >= 0xa0) || (c == 0xf0 && c1 < 0x90) ||
            (c == 0xf4 && c1 >= 0x90)) {
          ok = false;
        }
      }
      if (ok) n = want;
    }
    if (i + std::max<size_t>(n, 1) > max_bytes) {
      out += "...";
      return out;
    }
    if (n == 0) {
      escape(c);
      ++i;
    } else {
      out.append(bytes.substr(i, n));
      i += n;
    }
  }
  return out;
}

bool HostAllowed(std::string_view host, const HostRules& rules) {
  std::string_view name;
  std::string_view port;
  bool has_port = false;
  if (!host.empty() && host.front() == '[') {
    const size_t close = host.find(']');
    if (close == std::string_view::npos) return false;
    const std::string literal(host.substr(1, close - 1));
    in6_addr v6{};
    if (inet_pton(AF_INET6, literal.c_str(), &v6) != 1) return false;
    const std::string_view rest = host.substr(close + 1);
    if (!rest.empty() && rest.front() != ':') return false;
    has_port = !rest.empty();
    port = rest.empty() ? rest : rest.substr(1);
    name = {};  // an IP literal
  } else {
    const size_t colon = host.rfind(':');
    name = host.substr(0, colon);
    has_port = colon != std::string_view::npos;
    port = has_port ? host.substr(colon + 1) : std::string_view();
    if (name.empty()) return false;
  }
  if (has_port && (port.empty() || port.size() > 5)) return false;
  for (char c : port) {
    if (c < '0' || c > '9') return false;
  }
  if (name.empty()) return true;  // [IPv6]
  const std::string lower = Lower(name);
  in_addr v4{};
  if (inet_pton(AF_INET, lower.c_str(), &v4) == 1) return true;
  for (const std::string& allowed : rules.names) {
    if (Lower(allowed) == lower) return true;
  }
  return false;
}

Refusal ScreenHead(std::string_view head, const HostRules& rules) {
  if (head.size() > kMaxHeadBytes) {
    return Refuse(431,
                  "the request's head has more than " + std::to_string(kMaxHeadBytes) + " bytes");
  }
  if (head.size() < 4 || head.substr(head.size() - 4) != "\r\n\r\n") {
    return Refuse(400, "the request's head does not end with an empty line (CR LF CR LF)");
  }
  std::vector<std::string_view> lines;
  std::string_view rest = head.substr(0, head.size() - 2);  // each line keeps its own CR LF
  while (!rest.empty()) {
    const size_t lf = rest.find('\n');
    if (lf == std::string_view::npos || lf == 0 || rest[lf - 1] != '\r') {
      return Refuse(400, "a line of the request's head does not end with CR LF");
    }
    const std::string_view line = rest.substr(0, lf - 1);
    if (line.find('\r') != std::string_view::npos) {
      return Refuse(400, "a line of the request's head holds a bare CR");
    }
    lines.push_back(line);
    rest.remove_prefix(lf + 1);
  }
  if (lines.empty()) return Refuse(400, "the request has no request line");
  if (Refusal r = ScreenRequestLine(lines.front())) return r;
  if (lines.size() - 1 > kMaxHeaderLines) {
    return Refuse(431, "the request has " + std::to_string(lines.size() - 1) +
                           " header lines: at most " + std::to_string(kMaxHeaderLines) +
                           " are accepted");
  }
  return ScreenHeaders(lines, rules);
}

}  // namespace fetchscope::serve
