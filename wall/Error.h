#pragma once
// The exception wall/ throws at its boundary: a message a user can act on. It is a dfb::Error,
// so an app that catches dfb::Error catches ours too.
#include "dfb/Error.h"

namespace wall {

class Error : public dfb::Error {
 public:
  using dfb::Error::Error;
};

}  // namespace wall
