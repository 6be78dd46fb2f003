#pragma once
#include <stdexcept>
#include <string>

namespace vtb {

/// Bad input from a user: a file, a key, a value. The message is one line that names the
/// file, the key or element, and what is wrong; the CLI prints it and exits non-zero.
class InputError : public std::runtime_error {
public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

} // namespace vtb
