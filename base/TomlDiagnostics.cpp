#include "base/TomlDiagnostics.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace base {
namespace {

// An echoed line longer than this many code points is cut to a window around the column, so a
// minified or binary file cannot flood the terminal.
constexpr std::size_t kMaxEchoed = 120;
// Keys and values quoted in messages are cut to this many bytes.
constexpr std::size_t kMaxQuoted = 80;

// Control characters would garble the terminal (or split a message): shown as '?'.
std::string printable(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    const auto u = static_cast<unsigned char>(c);
    out += (u < 0x20 && c != '\t') || u == 0x7f ? '?' : c;
  }
  return out;
}

std::string quoted(std::string_view s) {
  return "'" + printable(s.substr(0, kMaxQuoted)) + (s.size() > kMaxQuoted ? "...'" : "'");
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// Edit distance counting a swap of neighbours as one edit (optimal string alignment), so both
// "orign" and "gird" are one edit from "origin" and "grid".
std::size_t editDistance(std::string_view a, std::string_view b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min(
          {d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

int clampInt(std::uint64_t v) { return static_cast<int>(std::min<std::uint64_t>(v, 1u << 30)); }

std::string numberText(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", v);
  return buffer;
}

std::string joined(std::span<const std::string_view> words) {
  std::string out;
  for (std::string_view w : words) out += (out.empty() ? "" : ", ") + std::string(w);
  return out;
}

}  // namespace

std::string Diagnostic::body() const {
  std::string out = field.empty() ? message : field + ": " + message;
  if (!excerpt.empty()) out += "\n" + excerpt;
  return out;
}

std::string Diagnostic::text() const {
  return where.known() ? where.text() + ": " + body() : body();
}

std::optional<std::string_view> closestKey(std::string_view word,
                                           std::span<const std::string_view> known) {
  // A typo is one edit in a short word, two in a longer one ("dims" is not a typo of "time").
  if (word.size() > 64) return std::nullopt;  // no key is that long; nor is the work worth it
  const std::string w = lower(word);
  const std::size_t allowed = w.size() <= 4 ? 1 : 2;
  std::optional<std::string_view> best;
  std::size_t bestDistance = allowed + 1;
  for (std::string_view candidate : known) {
    const std::size_t d = editDistance(w, lower(candidate));
    if (d < bestDistance && d < candidate.size()) bestDistance = d, best = candidate;
  }
  return best;
}

std::string sourceExcerpt(std::string_view text, int line, int column, int width) {
  if (line < 1) return {};
  std::size_t begin = 0;
  for (int l = 1; l < line; ++l) {
    begin = text.find('\n', begin);
    if (begin == std::string_view::npos) return {};
    ++begin;
  }
  if (begin > text.size()) return {};
  std::string_view s = text.substr(begin, text.find('\n', begin) - begin);
  if (!s.empty() && s.back() == '\r') s.remove_suffix(1);

  // Code points, as TOML++ counts columns: a byte that is not a UTF-8 continuation starts one.
  std::vector<std::size_t> starts;
  for (std::size_t i = 0; i < s.size(); ++i)
    if ((static_cast<unsigned char>(s[i]) & 0xC0) != 0x80) starts.push_back(i);
  const std::size_t n = starts.size();
  const std::size_t at = column > 0 ? std::min<std::size_t>(std::size_t(column) - 1, n) : 0;
  std::size_t first = 0, last = n;  // the code points shown
  if (n > kMaxEchoed) {
    first = at > kMaxEchoed / 2 ? std::min(at - kMaxEchoed / 2, n - kMaxEchoed) : 0;
    last = first + kMaxEchoed;
  }
  auto byteOf = [&](std::size_t cp) { return cp < n ? starts[cp] : s.size(); };
  const std::string head = first > 0 ? "..." : "";
  const std::string shown = head +
                            printable(s.substr(byteOf(first), byteOf(last) - byteOf(first))) +
                            (last < n ? "..." : "");

  const std::string number = std::to_string(line);
  const std::size_t gutter = std::max<std::size_t>(5, number.size() + 1);  // indented
  std::string out = std::string(gutter - number.size(), ' ') + number + " | " + shown;
  if (column > 0) {
    std::string caret(head.size(), ' ');
    for (std::size_t cp = first; cp < at && cp < last; ++cp)
      caret += s[starts[cp]] == '\t' ? '\t' : ' ';
    const std::size_t underline =
        std::min<std::size_t>(std::size_t(std::max(width, 1)) - 1, last > at ? last - at - 1 : 0);
    caret += '^' + std::string(underline, '~');
    out += "\n" + std::string(gutter, ' ') + " | " + caret;
  }
  return out;
}

std::string tomlTypeName(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table:
      return "a table";
    case toml::node_type::array:
      return "an array";
    case toml::node_type::string:
      return "a string";
    case toml::node_type::integer:
      return "an integer";
    case toml::node_type::floating_point:
      return "a floating-point number";
    case toml::node_type::boolean:
      return "a boolean";
    case toml::node_type::date:
      return "a date";
    case toml::node_type::time:
      return "a time";
    case toml::node_type::date_time:
      return "a date-time";
    default:
      return "nothing";
  }
}

TomlDiagnostics::TomlDiagnostics(std::string file, std::string text)
    : file_(std::move(file)), text_(std::move(text)) {}

bool TomlDiagnostics::readFile(std::string_view what) {
  std::error_code ec;
  if (std::filesystem::is_directory(file_, ec)) {
    keep({file_}, 1, "", "cannot read the " + std::string(what) + " (it is a folder)");
    return false;
  }
  std::ifstream in(file_, std::ios::binary);
  if (!in) {
    keep({file_}, 1, "",
         "cannot read the " + std::string(what) + " (" + std::strerror(errno) + ")");
    return false;
  }
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (in.bad()) {
    keep({file_}, 1, "", "cannot read the " + std::string(what) + " (a read failed)");
    return false;
  }
  text_ = std::move(bytes).str();
  return true;
}

std::optional<toml::table> TomlDiagnostics::parse() {
  try {
    return toml::parse(std::string_view(text_), std::string_view(file_));
  } catch (const toml::parse_error& e) {
    add(e);
    return std::nullopt;
  }
}

void TomlDiagnostics::add(const toml::node& at, std::string field, std::string message) {
  add(at.source(), std::move(field), std::move(message));
}

void TomlDiagnostics::add(const toml::key& at, std::string field, std::string message) {
  add(at.source(), std::move(field), std::move(message));
}

void TomlDiagnostics::add(const toml::source_region& at, std::string field, std::string message) {
  const int width = at.end.line == at.begin.line && at.end.column > at.begin.column
                        ? clampInt(at.end.column - at.begin.column)
                        : 1;
  keep({file_, clampInt(at.begin.line), clampInt(at.begin.column)}, width, std::move(field),
       std::move(message));
}

void TomlDiagnostics::add(int line, int column, std::string field, std::string message) {
  keep({file_, std::max(line, 0), line > 0 ? std::max(column, 0) : 0}, 1, std::move(field),
       std::move(message));
}

void TomlDiagnostics::add(const toml::parse_error& e) {
  const toml::source_position& p = e.source().begin;
  keep({file_, clampInt(p.line), clampInt(p.column)}, 1, "",
       "TOML syntax error: " + printable(e.description()));
}

void TomlDiagnostics::unknownKeys(const toml::table& t, std::string_view subject,
                                  std::span<const std::string_view> known) {
  for (auto&& [k, v] : t) {
    if (std::find(known.begin(), known.end(), k.str()) != known.end()) continue;
    std::string what =
        (subject.empty() ? "unknown table or key " : "unknown field ") + quoted(k.str());
    if (const auto best = closestKey(k.str(), known))
      what += " (did you mean '" + std::string(*best) + "'?)";
    what +=
        (subject.empty() ? "; the file's tables and keys: " : "; known fields: ") + joined(known);
    add(k, std::string(subject), std::move(what));
  }
}

std::optional<std::int64_t> TomlDiagnostics::integer(const toml::node& n, std::string_view field) {
  if (const auto* i = n.as_integer()) return i->get();
  add(n, std::string(field), "expected an integer, got " + tomlTypeName(n));
  return std::nullopt;
}

std::optional<double> TomlDiagnostics::number(const toml::node& n, std::string_view field) {
  if (const auto* i = n.as_integer()) return static_cast<double>(i->get());
  if (const auto* f = n.as_floating_point()) {
    if (std::isfinite(f->get())) return f->get();
    add(n, std::string(field), "expected a finite number, got " + numberText(f->get()));
    return std::nullopt;
  }
  add(n, std::string(field), "expected a number, got " + tomlTypeName(n));
  return std::nullopt;
}

std::optional<bool> TomlDiagnostics::boolean(const toml::node& n, std::string_view field) {
  if (const auto* b = n.as_boolean()) return b->get();
  add(n, std::string(field), "expected true or false, got " + tomlTypeName(n));
  return std::nullopt;
}

std::optional<std::string> TomlDiagnostics::string(const toml::node& n, std::string_view field) {
  if (const auto* s = n.as_string()) return s->get();
  add(n, std::string(field), "expected a string, got " + tomlTypeName(n));
  return std::nullopt;
}

const toml::table* TomlDiagnostics::table(const toml::node& n, std::string_view field) {
  if (const auto* t = n.as_table()) return t;
  add(n, std::string(field), "expected a table, got " + tomlTypeName(n));
  return nullptr;
}

const toml::array* TomlDiagnostics::array(const toml::node& n, std::string_view field) {
  if (const auto* a = n.as_array()) return a;
  add(n, std::string(field), "expected an array, got " + tomlTypeName(n));
  return nullptr;
}

namespace {

// The elements of an array of `count` values of one kind (0: any count), each read by `read`.
template <class T, class Read>
std::optional<std::vector<T>> elements(TomlDiagnostics& d, const toml::node& n,
                                       std::string_view field, std::size_t count,
                                       std::string_view shape, const char* kind, Read read) {
  const std::string expected =
      "expected " + std::string(shape) +
      (count > 0 ? " (" + std::to_string(count) + " " + kind + ")" : std::string());
  const toml::array* a = n.as_array();
  if (!a) {
    d.add(n, std::string(field), expected + ", got " + tomlTypeName(n));
    return std::nullopt;
  }
  if (count > 0 && a->size() != count) {
    d.add(
        n, std::string(field),
        expected + ", got " + std::to_string(a->size()) + " element" + (a->size() == 1 ? "" : "s"));
    return std::nullopt;
  }
  std::vector<T> out;
  bool ok = true;
  for (const toml::node& e : *a) {
    const std::optional<T> v = read(e);
    ok = ok && v.has_value();
    out.push_back(v.value_or(T{}));
  }
  if (!ok) return std::nullopt;
  return out;
}

}  // namespace

std::optional<std::vector<double>> TomlDiagnostics::numbers(const toml::node& n,
                                                            std::string_view field,
                                                            std::size_t count,
                                                            std::string_view shape) {
  return elements<double>(*this, n, field, count, shape, "numbers",
                          [&](const toml::node& e) { return number(e, field); });
}

std::optional<std::vector<std::int64_t>> TomlDiagnostics::integers(const toml::node& n,
                                                                   std::string_view field,
                                                                   std::size_t count,
                                                                   std::string_view shape) {
  return elements<std::int64_t>(*this, n, field, count, shape, "integers",
                                [&](const toml::node& e) { return integer(e, field); });
}

std::vector<std::string> TomlDiagnostics::texts() const {
  std::vector<std::string> out;
  for (const Diagnostic& d : kept_) out.push_back(d.text());
  if (count_ > kept_.size())
    out.push_back(file_ + ": and " + std::to_string(count_ - kept_.size()) + " more problems");
  return out;
}

void TomlDiagnostics::throwIfAny() const {
  if (kept_.empty()) return;
  std::string message = kept_.front().body();
  const std::vector<std::string> all = texts();
  for (std::size_t i = 1; i < all.size(); ++i) message += "\n" + all[i];
  throw Error(kept_.front().where, message);
}

void TomlDiagnostics::keep(SourceLocation where, int width, std::string field,
                           std::string message) {
  ++count_;
  if (kept_.size() >= kMaxKept) return;
  Diagnostic d{std::move(where), std::move(field), std::move(message), {}};
  d.excerpt = sourceExcerpt(text_, d.where.line, d.where.column, width);
  kept_.push_back(std::move(d));
}

}  // namespace base
