#include <gtest/gtest.h>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/solve/pcg.hpp"

namespace coarsegrain {
namespace {

/// Catches what f throws as an Error and rethrows it with a prefix, as the layers that add
/// context to an error's message do.
template <class F>
void with_context(F&& f) {
    try {
        f();
    } catch (const Error& e) {
        e.rethrow_with(std::string("context: ") + e.what());
    }
}

template <class E>
void expect_kept() {
    try {
        with_context([] { throw E("the message"); });
        FAIL() << "nothing thrown";
    } catch (const E& e) {
        EXPECT_STREQ(e.what(), "context: the message");
    } catch (...) {
        FAIL() << "the type was not kept";
    }
}

TEST(Error, RethrowWithKeepsTheType) {
    expect_kept<NotPositiveDefinite>();
    expect_kept<InvalidScene>();
    expect_kept<MeshReadError>();
    expect_kept<Interrupted>();
    expect_kept<solve::NotConverged>();
}

TEST(Error, RethrowWithKeepsAPlainError) {
    try {
        with_context([] { throw Error("plain"); });
        FAIL() << "nothing thrown";
    } catch (const NotPositiveDefinite&) {
        FAIL() << "a plain Error became a subclass";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "context: plain");
    }
}

}  // namespace
}  // namespace coarsegrain
