#include "base/errors.h"

#include <cerrno>

namespace fetchscope {

void ThrowPathError(const std::string& message, int error) {
  switch (error) {
    case ENOENT:
    case ENOTDIR:
    case EISDIR:
    case EEXIST:
    case EACCES:
    case EPERM:
    case EROFS:
    case ENAMETOOLONG:
    case ELOOP:
      throw UsageError(message);
    default:
      throw RunError(message);
  }
}

std::string Quoted(const std::string& s) { return "'" + s + "'"; }

}  // namespace fetchscope
