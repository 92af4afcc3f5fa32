#pragma once
// The one exception type of the renderers library: a message a user can act on, naming the file,
// line and field when the problem comes from a scene description.
#include <stdexcept>
#include <string>

namespace renderers {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace renderers
