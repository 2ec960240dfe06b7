#include "text_reader.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

namespace coarsegrain::io::detail {

namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

}  // namespace

std::string read_file_bytes(const std::string& file) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::file_status status = fs::status(file, ec);
    CG_VERIFY_AS(MeshReadError, fs::exists(status), "{}: cannot read: no such file", file);
    CG_VERIFY_AS(MeshReadError, fs::is_regular_file(status), "{}: cannot read: not a regular file",
                 file);
    std::ifstream in(file, std::ios::binary);
    CG_VERIFY_AS(MeshReadError, in.good(), "{}: cannot open: {}", file, std::strerror(errno));
    std::ostringstream buffer;
    buffer << in.rdbuf();
    CG_VERIFY_AS(MeshReadError, !in.bad(), "{}: read error", file);
    return std::move(buffer).str();
}

std::string quoted(std::string_view text) {
    constexpr std::size_t kMax = 60;
    std::string out = "'";
    for (std::size_t i = 0; i < text.size() && i < kMax; ++i) {
        const auto c = static_cast<unsigned char>(text[i]);
        if (c >= 0x20 && c < 0x7f)
            out += static_cast<char>(c);
        else
            out += fmt::format("\\x{:02x}", c);
    }
    if (text.size() > kMax) out += "...";
    return out + "'";
}

TextReader::TextReader(std::string file, char comment)
    : m_file(std::move(file)), m_data(read_file_bytes(m_file)), m_comment(comment) {}

bool TextReader::empty() const {
    bool in_comment = false;
    for (char c : m_data) {
        if (c == '\n')
            in_comment = false;
        else if (m_comment != '\0' && c == m_comment)
            in_comment = true;
        else if (!in_comment && !is_space(c))
            return false;
    }
    return true;
}

bool TextReader::next_line() {
    m_fields.clear();
    m_next_token = 0;
    while (m_pos < m_data.size()) {
        const std::size_t end = std::min(m_data.find('\n', m_pos), m_data.size());
        ++m_line;
        std::string_view text(m_data.data() + m_pos, end - m_pos);
        m_pos = end < m_data.size() ? end + 1 : end;
        if (m_comment != '\0') text = text.substr(0, text.find(m_comment));
        m_line_text = text;
        std::size_t i = 0;
        while (i < text.size()) {
            while (i < text.size() && is_space(text[i])) ++i;
            const std::size_t start = i;
            while (i < text.size() && !is_space(text[i])) ++i;
            if (i > start) m_fields.push_back(text.substr(start, i - start));
        }
        if (!m_fields.empty()) return true;
    }
    m_line_text = {};
    return false;
}

void TextReader::require_line(std::string_view what) {
    if (!next_line()) fail("unexpected end of file: expected {} (is the file truncated?)", what);
}

void TextReader::expect_fields(std::size_t n, std::string_view what) const {
    if (m_fields.size() != n)
        fail("expected {} ({} fields), found {} field{}: {}", what, n, m_fields.size(),
             m_fields.size() == 1 ? "" : "s", quoted(m_line_text));
}

bool TextReader::next_token(std::string_view& token) {
    while (m_next_token >= m_fields.size()) {
        if (!next_line()) return false;
    }
    token = m_fields[m_next_token++];
    return true;
}

std::string_view TextReader::require_token(std::string_view what) {
    std::string_view token;
    if (!next_token(token))
        fail("unexpected end of file: expected {} (is the file truncated?)", what);
    return token;
}

std::int64_t TextReader::integer(std::string_view token, std::string_view what) const {
    std::string_view digits = token;
    if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
    std::int64_t value = 0;
    const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (ec == std::errc::result_out_of_range)
        fail("expected {}, found {}, which is out of the 64-bit integer range", what,
             quoted(token));
    if (ec != std::errc() || ptr != digits.data() + digits.size() || digits.empty())
        fail("expected {} (an integer), found {}", what, quoted(token));
    return value;
}

Index TextReader::count(std::string_view token, std::string_view what) const {
    const std::int64_t value = integer(token, what);
    if (value < 0) fail("expected {} (a count >= 0), found {}", what, value);
    if (value > std::numeric_limits<Index>::max())
        fail("{} is {}, more than coarsegrain supports ({})", what, value,
             std::numeric_limits<Index>::max());
    return static_cast<Index>(value);
}

Index TextReader::int32(std::string_view token, std::string_view what) const {
    const std::int64_t value = integer(token, what);
    if (value < std::numeric_limits<Index>::min() || value > std::numeric_limits<Index>::max())
        fail("expected {} (a 32-bit integer), found {}", what, value);
    return static_cast<Index>(value);
}

double TextReader::real(std::string_view token, std::string_view what) const {
    std::string_view digits = token;
    if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
    double value = 0;
    const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (ec == std::errc::result_out_of_range)
        fail("expected {}, found {}, which is out of the double range", what, quoted(token));
    if (ec != std::errc() || ptr != digits.data() + digits.size() || digits.empty())
        fail("expected {} (a number), found {}", what, quoted(token));
    if (!std::isfinite(value)) fail("expected {} (a finite number), found {}", what, quoted(token));
    return value;
}

void TextReader::fail_at(int line, const std::string& message) const {
    throw MeshReadError(fmt::format("{}:{}: {}", m_file, std::max(line, 1), message));
}

}  // namespace coarsegrain::io::detail
