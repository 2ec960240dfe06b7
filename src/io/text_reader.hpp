#pragma once
/// @file Internal: a line and token reader for text mesh formats that reports every error as
/// MeshReadError "FILE:LINE: what was expected, what was found".
#include <fmt/format.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/types.hpp"

namespace coarsegrain::io::detail {

/// Reads a whole file to memory. @throws MeshReadError naming the file if it cannot be read
std::string read_file_bytes(const std::string& file);

/// `text` in single quotes for an error message: at most 60 characters, control and non-ASCII
/// bytes shown as \xNN (fuzzed or binary input stays readable).
std::string quoted(std::string_view text);

/// Text file reader. Lines are split into whitespace-separated fields; blank lines and, if a
/// comment character is given, everything from it to the end of the line are skipped.
/// Line mode (next_line / fields) and token mode (next_token, tokens across lines) can be
/// mixed: token mode continues after the last token handed out on the current line.
class TextReader {
  public:
    /// @param comment character that starts a comment running to the end of the line, or '\0'
    TextReader(std::string file, char comment);

    const std::string& file() const { return m_file; }
    /// Number of the current line (1-based); 0 before the first line.
    int line() const { return m_line; }
    /// True if the file has no field at all (only blanks and comments).
    bool empty() const;

    /// Moves to the next line that holds at least one field; false at the end of the file.
    bool next_line();
    /// next_line(), failing with "unexpected end of file: expected WHAT" at the end.
    void require_line(std::string_view what);
    /// Fields of the current line.
    const std::vector<std::string_view>& fields() const { return m_fields; }
    std::string_view field(std::size_t i) const { return m_fields[i]; }
    std::size_t num_fields() const { return m_fields.size(); }
    /// The current line as text (for messages).
    std::string_view line_text() const { return m_line_text; }
    /// Fails unless the current line has exactly n fields.
    void expect_fields(std::size_t n, std::string_view what) const;

    /// Next token, continuing on following lines; false at the end of the file.
    bool next_token(std::string_view& token);
    /// next_token(), failing with "unexpected end of file: expected WHAT" at the end.
    std::string_view require_token(std::string_view what);

    /// A decimal integer. @throws MeshReadError "expected WHAT (an integer), found '...'"
    std::int64_t integer(std::string_view token, std::string_view what) const;
    /// An integer in [0, 2^31-1], the range of Index: element/node counts. Absurd or negative
    /// counts are reported here, before anything is allocated for them.
    Index count(std::string_view token, std::string_view what) const;
    /// An integer that fits in Index (material ids, signed).
    Index int32(std::string_view token, std::string_view what) const;
    /// A finite floating-point number.
    double real(std::string_view token, std::string_view what) const;
    /// Bytes not yet read: an upper bound on how many more records the file can hold.
    std::size_t bytes_left() const { return m_data.size() - m_pos; }

    /// @throws MeshReadError "FILE:LINE: message"
    template <class... Args>
    [[noreturn]] void fail(fmt::format_string<Args...> format, Args&&... args) const {
        fail_at(m_line, fmt::format(format, std::forward<Args>(args)...));
    }
    /// @throws MeshReadError "FILE:LINE: message" for another line
    [[noreturn]] void fail_at(int line, const std::string& message) const;

  private:
    std::string m_file;
    std::string m_data;
    char m_comment;
    std::size_t m_pos = 0;
    int m_line = 0;
    std::string_view m_line_text;
    std::vector<std::string_view> m_fields;
    std::size_t m_next_token = 0;  ///< token mode: next field of the current line to hand out
};

/// min(count, bytes_left / bytes_per_record): how many records to reserve room for, so that
/// an absurd count in a small file never allocates more than the file could hold.
inline std::size_t reserve_hint(Index count, std::size_t bytes_left, std::size_t bytes_per_record) {
    const std::size_t fit = bytes_left / bytes_per_record + 1;
    return static_cast<std::size_t>(count) < fit ? static_cast<std::size_t>(count) : fit;
}

}  // namespace coarsegrain::io::detail
