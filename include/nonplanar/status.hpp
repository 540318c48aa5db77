// Status codes and a minimal expected-value type for the public API.
// Errors are values, never exit() or an exception escaping the library.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <variant>

namespace nonplanar {

/// What went wrong. `ok` is never stored in an Error.
enum class Status {
  ok = 0,
  invalid_argument,  ///< a parameter is out of range (names the key)
  io_error,          ///< a file could not be opened, read or written
  parse_error,       ///< a file's content is malformed (names the line or byte)
  invalid_mesh,      ///< the mesh is unusable (no faces, non-finite coordinates, ...)
  cancelled,         ///< the Context's cancel flag was raised
  unsupported,       ///< a format or feature we do not handle
  internal_error,
};

/// Short lower-case name of a status, e.g. "parse error".
const char* status_name(Status s);

/// An error: the status and one line of text. For file problems the text starts with the
/// file name: "FILE: what is wrong".
struct Error {
  Status status = Status::internal_error;
  std::string message;
};

/// Either a value or an Error (std::expected is C++23; this is the small subset we need).
/// [[nodiscard]]: a result nobody looks at is an error nobody sees.
template <class T>
class [[nodiscard]] Expected {
 public:
  Expected(T value) : v_(std::move(value)) {}      // NOLINT: implicit on purpose
  Expected(Error error) : v_(std::move(error)) {}  // NOLINT
  bool ok() const { return std::holds_alternative<T>(v_); }
  explicit operator bool() const { return ok(); }
  T& value() & { return std::get<T>(v_); }
  const T& value() const& { return std::get<T>(v_); }
  T&& value() && { return std::get<T>(std::move(v_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }
  T&& operator*() && { return std::move(*this).value(); }
  const Error& error() const { return std::get<Error>(v_); }

 private:
  std::variant<T, Error> v_;
};

/// Success or an Error, for an operation with no value to return.
template <>
class [[nodiscard]] Expected<void> {
 public:
  Expected() = default;
  Expected(Error error) : e_(std::move(error)) {}  // NOLINT: implicit on purpose
  bool ok() const { return !e_; }
  explicit operator bool() const { return ok(); }
  const Error& error() const { return *e_; }

 private:
  std::optional<Error> e_;
};

}  // namespace nonplanar
