#pragma once
// The one way a TOML input (a layout, a scene, a camera path) says what is wrong with it. Every
// problem names the file, line, column and field, echoes the line with a caret under the column
// and, for an unknown key, suggests the closest known one; all problems of a file are collected,
// then thrown as one base::Error (or listed, for a caller that lists problems).
#include <toml++/toml.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "base/Error.h"

namespace base {

// One problem in an input file.
struct Diagnostic {
  SourceLocation where;
  std::string field;    // what it is about: "camera.fov", "display 'a'.size"; may be empty
  std::string message;  // what is wrong, and what would be right
  std::string excerpt;  // the line at `where` with a caret under the column; may be empty

  // "FIELD: MESSAGE", then the excerpt on the lines below: all but the location.
  std::string body() const;
  // "FILE:LINE:COLUMN: FIELD: MESSAGE", then the excerpt.
  std::string text() const;
};

// The entry of `known` closest to `word` (ignoring case), when it is close enough to be a typo.
std::optional<std::string_view> closestKey(std::string_view word,
                                           std::span<const std::string_view> known);

// Line `line` of `text` (from 1) and under it a caret at `column` (code points, from 1),
// underlined for `width` code points; empty when the text has no such line.
std::string sourceExcerpt(std::string_view text, int line, int column, int width = 1);

// "a string", "an integer", "a table": a TOML node's type as messages name it.
std::string tomlTypeName(const toml::node& n);

class TomlDiagnostics {
 public:
  // At most this many problems are kept and printed; the rest are counted.
  static constexpr std::size_t kMaxKept = 100;

  // `text` is the file's contents, echoed under each problem; none given, none echoed.
  explicit TomlDiagnostics(std::string file, std::string text = {});

  // Reads the file into text(); false, with "FILE: cannot read the WHAT (reason)" recorded, when
  // it cannot.
  bool readFile(std::string_view what);
  // Parses text(); nothing, with the syntax error recorded at its place, when it is not TOML.
  std::optional<toml::table> parse();

  const std::string& file() const { return file_; }
  const std::string& text() const { return text_; }

  void add(const toml::node& at, std::string field, std::string message);
  void add(const toml::key& at, std::string field, std::string message);
  void add(const toml::source_region& at, std::string field, std::string message);
  // A place known by line and column alone (0: unknown), e.g. one stored while reading.
  void add(int line, int column, std::string field, std::string message);
  // A syntax error, at its own place.
  void add(const toml::parse_error& e);

  // Reports every key of `t` that is not in `known`, suggesting the closest. `subject` names the
  // table ("camera", "display 'a'"); empty for the file's top level.
  void unknownKeys(const toml::table& t, std::string_view subject,
                   std::span<const std::string_view> known);

  // Typed readers: the value, or nothing with "FIELD: expected T, got U" recorded at the node.
  std::optional<std::int64_t> integer(const toml::node& n, std::string_view field);
  // An integer or a finite floating-point number.
  std::optional<double> number(const toml::node& n, std::string_view field);
  std::optional<bool> boolean(const toml::node& n, std::string_view field);
  std::optional<std::string> string(const toml::node& n, std::string_view field);
  const toml::table* table(const toml::node& n, std::string_view field);
  const toml::array* array(const toml::node& n, std::string_view field);
  // An array of exactly `count` numbers (integers); `shape` shows it in the message ("[x, y]").
  // A wrong element is reported at the element, and every element is checked.
  std::optional<std::vector<double>> numbers(const toml::node& n, std::string_view field,
                                             std::size_t count, std::string_view shape);
  std::optional<std::vector<std::int64_t>> integers(const toml::node& n, std::string_view field,
                                                    std::size_t count, std::string_view shape);

  // Problems so far, counting those past kMaxKept.
  std::size_t count() const { return count_; }
  bool ok() const { return count_ == 0; }
  const std::vector<Diagnostic>& problems() const { return kept_; }
  // Each problem's text, and a last line saying how many more there were past kMaxKept.
  std::vector<std::string> texts() const;
  // Throws one base::Error listing every problem, located at the first; returns if there is none.
  void throwIfAny() const;

 private:
  void keep(SourceLocation where, int width, std::string field, std::string message);

  std::string file_;
  std::string text_;
  std::vector<Diagnostic> kept_;
  std::size_t count_ = 0;
};

}  // namespace base
