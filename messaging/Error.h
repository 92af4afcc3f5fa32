#pragma once
// The one exception type the messaging layer throws (and the DFB, which throws it as dfb::Error,
// dfb/Error.h): a message a user can act on.
#include <stdexcept>
#include <string>

namespace messaging {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A wait passed its deadline: another rank did not do its part in time. Kept apart so the app
// can find out which rank before it ends the job (Messenger::probePeers).
class DeadlineError : public Error {
 public:
  using Error::Error;
};

// Turns an MPI return code into an Error naming the call; MPI_SUCCESS passes through.
void checkMpi(int code, const char* call);

}  // namespace messaging
