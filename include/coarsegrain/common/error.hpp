#pragma once
/// @file Error policy (STYLE.md 3.5).
///
/// - CG_VERIFY(cond, fmt, args...): always on; for bad input or numerical failures a user can
///   cause. Throws coarsegrain::Error (or the subclass given to CG_VERIFY_AS) with a message
///   that says what failed, the offending value, and what to change.
/// - CG_ASSERT(cond, msg): internal contracts, debug builds only.
#include <fmt/format.h>

#include <cassert>
#include <exception>
#include <stdexcept>
#include <string>

namespace coarsegrain {

/// Base of every error coarsegrain reports to a user.
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
    /// Throws an error of this one's type with `message`: a caller that adds context to the
    /// message of an error it catches keeps its type (a NotPositiveDefinite stays one).
    [[noreturn]] void rethrow_with(const std::string& message) const {
        std::rethrow_exception(with_message(message));
    }

protected:
    /// An error of this one's type with `message` (ErrorOf overrides it).
    virtual std::exception_ptr with_message(const std::string& message) const {
        return std::make_exception_ptr(Error(message));
    }
};

/// Base of Error's subclasses: gives them rethrow_with (class E : public ErrorOf<E>).
template <class Derived>
class ErrorOf : public Error {
public:
    using Error::Error;

protected:
    std::exception_ptr with_message(const std::string& message) const override {
        return std::make_exception_ptr(Derived(message));
    }
};

/// A scene file is invalid; the message names the JSON key.
class InvalidScene : public ErrorOf<InvalidScene> {
public:
    using ErrorOf::ErrorOf;
};

/// A mesh file could not be read; the message names the file and line.
class MeshReadError : public ErrorOf<MeshReadError> {
public:
    using ErrorOf::ErrorOf;
};

/// A matrix that must be symmetric positive definite is not (e.g. no Dirichlet condition).
class NotPositiveDefinite : public ErrorOf<NotPositiveDefinite> {
public:
    using ErrorOf::ErrorOf;
};

/// A computation stopped because request_interrupt() was called (progress.hpp, Phase).
class Interrupted : public ErrorOf<Interrupted> {
public:
    using ErrorOf::ErrorOf;
};

namespace detail {
template <class E = Error>
[[noreturn]] void fail(const std::string& message) {
    throw E(message);
}
}  // namespace detail

}  // namespace coarsegrain

#define CG_VERIFY(cond, ...)                                                   \
    do {                                                                       \
        if (!(cond)) ::coarsegrain::detail::fail(fmt::format(__VA_ARGS__));    \
    } while (0)

#define CG_VERIFY_AS(ErrorType, cond, ...)                                              \
    do {                                                                                \
        if (!(cond)) ::coarsegrain::detail::fail<ErrorType>(fmt::format(__VA_ARGS__));  \
    } while (0)

#define CG_ASSERT(cond, msg) assert((cond) && (msg))
