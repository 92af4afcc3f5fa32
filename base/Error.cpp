#include "base/Error.h"

#include <mpi.h>

namespace base {

std::string SourceLocation::text() const {
  std::string out = file;
  if (line > 0) out += ":" + std::to_string(line);
  if (line > 0 && column > 0) out += ":" + std::to_string(column);
  return out;
}

Error::Error(const std::string& message) : std::runtime_error(message), message_(message) {}

Error::Error(SourceLocation where, const std::string& message)
    : std::runtime_error(where.known() ? where.text() + ": " + message : message),
      where_(std::move(where)),
      message_(message) {}

void checkMpi(int code, const char* call) {
  if (code == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(code, text, &length);
  throw Error(std::string(call) + " failed: " + std::string(text, static_cast<size_t>(length)));
}

}  // namespace base
