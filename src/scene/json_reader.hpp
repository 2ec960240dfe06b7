#pragma once
// Typed, validating access to a JSON value that remembers its key path for error messages.
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/types.hpp"

namespace coarsegrain::scene {

class JsonReader {
public:
    JsonReader(const nlohmann::json& j, std::string path, const std::string& source)
        : m_j(j), m_path(std::move(path)), m_source(source) {}

    const nlohmann::json& json() const { return m_j; }
    const std::string& path() const { return m_path; }
    bool has(const std::string& key) const { return m_j.is_object() && m_j.contains(key); }

    /// The member `key`, which must exist.
    JsonReader at(const std::string& key) const {
        require_object();
        fail_unless(m_j.contains(key), "missing key \"{}\"", key);
        return JsonReader(m_j.at(key), child(key), m_source);
    }
    /// Element i of an array.
    JsonReader at(std::size_t i) const {
        return JsonReader(m_j.at(i), fmt::format("{}[{}]", m_path, i), m_source);
    }
    std::optional<JsonReader> find(const std::string& key) const {
        require_object();
        if (!m_j.contains(key)) return std::nullopt;
        return JsonReader(m_j.at(key), child(key), m_source);
    }

    void require_object() const { fail_unless(m_j.is_object(), "expected an object"); }
    std::size_t array_size() const {
        fail_unless(m_j.is_array(), "expected an array");
        return m_j.size();
    }
    /// Rejects keys not in `allowed`.
    void allow_only(std::initializer_list<const char*> allowed) const {
        require_object();
        for (const auto& [key, value] : m_j.items()) {
            bool ok = false;
            for (const char* a : allowed) ok = ok || key == a;
            if (!ok) {
                std::string list;
                for (const char* a : allowed) list += fmt::format("{}\"{}\"", list.empty() ? "" : ", ", a);
                fail_key(key, "unknown key; expected one of {}", list);
            }
        }
    }

    double number() const {
        fail_unless(m_j.is_number(), "expected a number, got {}", m_j.dump());
        const double v = m_j.get<double>();
        fail_unless(std::isfinite(v), "expected a finite number");
        return v;
    }
    double positive() const {
        const double v = number();
        fail_unless(v > 0, "expected a positive number, got {}", v);
        return v;
    }
    /// An integer in [lo, hi] (JSON integers are 64-bit; nothing is narrowed silently).
    std::int64_t integer(std::int64_t lo, std::int64_t hi) const {
        fail_unless(m_j.is_number_integer(), "expected an integer, got {}", m_j.dump());
        constexpr auto kMax = static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
        const bool fits = !m_j.is_number_unsigned() || m_j.get<std::uint64_t>() <= kMax;
        const std::int64_t v = fits ? m_j.get<std::int64_t>() : 0;
        fail_unless(fits && v >= lo && v <= hi, "expected an integer in [{}, {}], got {}", lo, hi,
                    m_j.dump());
        return v;
    }
    /// An integer that fits an int.
    int integer() const {
        return static_cast<int>(integer(std::numeric_limits<int>::min(),
                                        std::numeric_limits<int>::max()));
    }
    bool boolean() const {
        fail_unless(m_j.is_boolean(), "expected true or false, got {}", m_j.dump());
        return m_j.get<bool>();
    }
    std::string string() const {
        fail_unless(m_j.is_string(), "expected a string, got {}", m_j.dump());
        return m_j.get<std::string>();
    }
    /// A string among `choices`; returns its position.
    std::size_t choice(std::initializer_list<const char*> choices) const {
        const std::string s = string();
        std::string quoted;
        std::size_t i = 0;
        for (const char* c : choices) {
            if (s == c) return i;
            quoted += fmt::format("{}\"{}\"", i++ == 0 ? "" : ", ", c);
        }
        fail("unknown value \"{}\"; expected one of {}", s, quoted);
    }
    /// An array of exactly n finite numbers.
    Eigen::VectorXd vector(int n) const {
        fail_unless(m_j.is_array() && static_cast<int>(m_j.size()) == n,
                    "expected {} numbers, got {}", n, m_j.dump());
        Eigen::VectorXd v(n);
        for (int i = 0; i < n; ++i) v[i] = at(static_cast<std::size_t>(i)).number();
        return v;
    }

    template <class... Args>
    void fail_unless(bool ok, fmt::format_string<Args...> f, Args&&... args) const {
        if (!ok) fail(f, std::forward<Args>(args)...);
    }
    /// Throws InvalidScene "<source>: <path>: <message>" (no path at the root).
    template <class... Args>
    [[noreturn]] void fail(fmt::format_string<Args...> f, Args&&... args) const {
        fail_at(m_path, fmt::format(f, std::forward<Args>(args)...));
    }

private:
    std::string child(const std::string& key) const {
        return m_path.empty() ? key : m_path + "." + key;
    }
    template <class... Args>
    [[noreturn]] void fail_key(const std::string& key, fmt::format_string<Args...> f,
                               Args&&... args) const {
        fail_at(child(key), fmt::format(f, std::forward<Args>(args)...));
    }
    [[noreturn]] void fail_at(const std::string& path, const std::string& message) const {
        detail::fail<InvalidScene>(path.empty()
                                       ? fmt::format("{}: {}", m_source, message)
                                       : fmt::format("{}: {}: {}", m_source, path, message));
    }

    const nlohmann::json& m_j;
    std::string m_path;
    const std::string& m_source;
};

}  // namespace coarsegrain::scene
