#pragma once
// The DFB throws the messaging layer's error type (messaging/Error.h): dfb::Error is the DFB's
// exception, the same class the Messenger throws.
#include "messaging/Error.h"

namespace dfb {

using Error = messaging::Error;
using DeadlineError = messaging::DeadlineError;
using messaging::checkMpi;

}  // namespace dfb
