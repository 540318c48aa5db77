#include "nonplanar/status.hpp"

namespace nonplanar {

const char* status_name(Status s) {
  switch (s) {
    case Status::ok:
      return "ok";
    case Status::invalid_argument:
      return "invalid argument";
    case Status::io_error:
      return "i/o error";
    case Status::parse_error:
      return "parse error";
    case Status::invalid_mesh:
      return "invalid mesh";
    case Status::cancelled:
      return "cancelled";
    case Status::unsupported:
      return "unsupported";
    case Status::internal_error:
      return "internal error";
  }
  return "unknown";
}

}  // namespace nonplanar
