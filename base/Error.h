#pragma once
// The one exception type of dfbwall, thrown by every layer: a message a user can act on and,
// when the problem comes from a file, where in it (file, line, column). what() is the printed
// form, "FILE:LINE:COLUMN: message", so every catch prints it the same way.
#include <stdexcept>
#include <string>

namespace base {

// A place in an input file. line and column count from 1; 0 means unknown.
struct SourceLocation {
  std::string file;
  int line = 0;
  int column = 0;

  bool known() const { return !file.empty(); }
  // "FILE:LINE:COLUMN", "FILE:LINE" or "FILE", as much as is known.
  std::string text() const;
};

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message);
  Error(SourceLocation where, const std::string& message);

  // Where in a file the problem is; not known() for problems that come from no file.
  const SourceLocation& where() const { return where_; }
  // The message without the location.
  const std::string& message() const { return message_; }

 private:
  SourceLocation where_;
  std::string message_;
};

// A wait passed its deadline: another rank did not do its part in time. Kept apart so the app
// can find out which rank before it ends the job (Messenger::probePeers).
class DeadlineError : public Error {
 public:
  using Error::Error;
};

// Turns an MPI return code into an Error naming the call; MPI_SUCCESS passes through.
void checkMpi(int code, const char* call);

}  // namespace base
