// Small helpers shared by the report programs (hardcases, validate, accuracy, effects): JSON
// scalars, Markdown cells, list options and the run's context. Header-only: no library needed.
#pragma once

#include <cerrno>
#include <cmath>
#include <optional>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <sstream>
#include <string_view>
#include <vector>

namespace quadrant::report {

/// A whole decimal integer in [least, most], or nothing (empty, trailing characters, overflow
/// or out of range): the caller reports the flag.
inline std::optional<int> ParseInt(const std::string& text, long least, long most) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno != 0 || v < least || v > most) return std::nullopt;
  return int(v);
}

/// The items of a comma-separated command-line list ("a,b,c"), empty items dropped.
inline std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

/// A JSON string literal (quoted, escaped).
inline std::string JsonString(std::string_view s) {
  std::string out = "\"";
  for (char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buffer[8];
          std::snprintf(buffer, sizeof buffer, "\\u%04x", c);
          out += buffer;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

/// A JSON number with 9 significant digits (enough for float read-back); null if not finite,
/// which JSON cannot write.
inline std::string JsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.9g", v);
  return buffer;
}

/// A number for a Markdown table: 4 significant digits, "NaN"/"inf" spelled out.
inline std::string Cell(double v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.4g", v);
  return buffer;
}

/// A table cell's text with the characters Markdown tables cannot hold made harmless.
inline std::string CellText(std::string_view s) {
  std::string out;
  for (char c : s) out += c == '|' ? '/' : (c == '\n' ? ' ' : c);
  return out;
}

/// An environment variable, or `fallback` when unset or empty. tools/quadrant sets
/// QUADRANT_MACHINE and QUADRANT_COMMIT for the reports.
inline std::string Env(const char* name, const char* fallback) {
  const char* v = std::getenv(name);
  return v && *v ? v : fallback;
}

/// UTC time now, ISO 8601.
inline std::string UtcNow() {
  std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buffer;
}

}  // namespace quadrant::report
