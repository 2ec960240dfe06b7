#include "xml.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "coarsegrain/common/error.hpp"
#include "text_reader.hpp"

namespace coarsegrain::io::detail {

const std::string* XmlElement::attribute(std::string_view key) const {
    for (const auto& [k, v] : attributes)
        if (k == key) return &v;
    return nullptr;
}

std::vector<const XmlElement*> XmlDocument::children(const XmlElement& parent,
                                                     std::string_view name) const {
    std::vector<const XmlElement*> out;
    for (int c : parent.children)
        if (elements[c].name == name) out.push_back(&elements[c]);
    return out;
}

namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }
bool is_name_char(char c) { return !is_space(c) && c != '/' && c != '>' && c != '=' && c != '<'; }

class XmlParser {
  public:
    XmlParser(std::string file, std::string text) {
        m_doc.file = std::move(file);
        m_doc.text = std::move(text);
    }

    XmlDocument parse() {
        const std::string& s = m_doc.text;
        std::vector<int> open;
        bool have_root = false;
        std::size_t pos = 0;
        while (true) {
            const std::size_t lt = s.find('<', pos);
            if (lt == std::string::npos) break;
            pos = lt;
            if (s.compare(pos, 4, "<!--") == 0) {
                pos = skip_past(pos, "-->", "comment");
            } else if (s.compare(pos, 9, "<![CDATA[") == 0) {
                pos = skip_past(pos, "]]>", "CDATA section");
            } else if (s.compare(pos, 2, "<?") == 0) {
                pos = skip_past(pos, "?>", "processing instruction");
            } else if (s.compare(pos, 2, "<!") == 0) {
                pos = skip_past(pos, ">", "declaration");
            } else if (s.compare(pos, 2, "</") == 0) {
                const std::size_t gt = s.find('>', pos);
                if (gt == std::string::npos) fail(pos, "unterminated end tag");
                std::string_view name = std::string_view(s).substr(pos + 2, gt - pos - 2);
                while (!name.empty() && is_space(name.back())) name.remove_suffix(1);
                if (open.empty()) fail(pos, fmt::format("end tag </{}> without a start tag", name));
                XmlElement& top = m_doc.elements[open.back()];
                if (name != top.name)
                    fail(pos, fmt::format("expected </{}> (opened on line {}), found </{}>",
                                          top.name, top.line, name));
                if (top.name != "AppendedData") top.content_end = pos;
                open.pop_back();
                pos = gt + 1;
            } else {
                if (have_root && open.empty())
                    fail(pos, "a second top-level element; an XML file has one root");
                have_root = true;
                bool self_closing = false;
                const int index = start_tag(pos, self_closing);
                if (!open.empty()) m_doc.elements[open.back()].children.push_back(index);
                XmlElement& e = m_doc.elements[index];
                e.content_begin = e.content_end = pos;
                if (self_closing) continue;
                open.push_back(index);
                if (e.name == "AppendedData") {
                    // Raw appended data may hold any byte: jump to its end tag.
                    const std::size_t underscore = s.find('_', pos);
                    const std::size_t end = s.rfind("</AppendedData");
                    if (underscore == std::string::npos || end == std::string::npos ||
                        end < underscore)
                        fail(pos,
                             "<AppendedData> needs a '_' marker before its data and an "
                             "</AppendedData> end tag");
                    e.content_begin = underscore + 1;
                    e.content_end = end;
                    pos = end;
                }
            }
        }
        if (!open.empty()) {
            const XmlElement& e = m_doc.elements[open.back()];
            fail(s.size(), fmt::format("unexpected end of file: <{}> (line {}) is not closed",
                                       e.name, e.line));
        }
        if (!have_root) fail(s.size(), "no XML element found");
        return std::move(m_doc);
    }

  private:
    int line_at(std::size_t pos) {
        // Positions are visited in increasing order, except after a failure.
        if (pos < m_line_pos) {
            m_line_pos = 0;
            m_line = 1;
        }
        const std::string& s = m_doc.text;
        m_line += static_cast<int>(std::count(s.begin() + static_cast<std::ptrdiff_t>(m_line_pos),
                                              s.begin() + static_cast<std::ptrdiff_t>(pos), '\n'));
        m_line_pos = pos;
        return m_line;
    }

    [[noreturn]] void fail(std::size_t pos, const std::string& message) {
        throw MeshReadError(fmt::format("{}:{}: {}", m_doc.file, line_at(pos), message));
    }

    std::size_t skip_past(std::size_t pos, const char* end, const char* what) {
        const std::size_t at = m_doc.text.find(end, pos);
        if (at == std::string::npos) fail(pos, fmt::format("unterminated {}", what));
        return at + std::string_view(end).size();
    }

    std::string decode_entities(std::size_t pos, std::string_view raw) {
        std::string out;
        for (std::size_t i = 0; i < raw.size(); ++i) {
            if (raw[i] != '&') {
                out += raw[i];
                continue;
            }
            const std::size_t semi = raw.find(';', i);
            if (semi == std::string_view::npos) fail(pos, "'&' without ';' in an attribute value");
            const std::string_view entity = raw.substr(i + 1, semi - i - 1);
            if (entity == "amp")
                out += '&';
            else if (entity == "lt")
                out += '<';
            else if (entity == "gt")
                out += '>';
            else if (entity == "quot")
                out += '"';
            else if (entity == "apos")
                out += '\'';
            else
                fail(pos, fmt::format("unknown entity {}", quoted(entity)));
            i = semi;
        }
        return out;
    }

    /// Parses '<name attr="value" ...>' or '.../>' at pos; pos ends after it.
    int start_tag(std::size_t& pos, bool& self_closing) {
        const std::string& s = m_doc.text;
        const std::size_t tag = pos;
        XmlElement e;
        e.line = line_at(tag);
        std::size_t i = pos + 1;
        while (i < s.size() && is_name_char(s[i])) ++i;
        e.name = s.substr(pos + 1, i - pos - 1);
        if (e.name.empty()) fail(tag, "expected an element name after '<'");
        while (true) {
            while (i < s.size() && is_space(s[i])) ++i;
            if (i >= s.size()) fail(tag, fmt::format("unterminated start tag <{}>", e.name));
            if (s[i] == '>') {
                ++i;
                break;
            }
            if (s.compare(i, 2, "/>") == 0) {
                self_closing = true;
                i += 2;
                break;
            }
            const std::size_t k = i;
            while (i < s.size() && is_name_char(s[i])) ++i;
            if (i == k)
                fail(tag, fmt::format("expected an attribute name in <{}>, found {}", e.name,
                                      quoted(std::string_view(s).substr(i, 10))));
            std::string key = s.substr(k, i - k);
            while (i < s.size() && is_space(s[i])) ++i;
            if (i >= s.size() || s[i] != '=')
                fail(tag, fmt::format("expected '=' after attribute {} of <{}>", key, e.name));
            ++i;
            while (i < s.size() && is_space(s[i])) ++i;
            if (i >= s.size() || (s[i] != '"' && s[i] != '\''))
                fail(tag,
                     fmt::format("expected a quoted value for attribute {} of <{}>", key, e.name));
            const char q = s[i];
            const std::size_t close = s.find(q, i + 1);
            if (close == std::string::npos)
                fail(tag, fmt::format("unterminated value of attribute {} of <{}>", key, e.name));
            e.attributes.emplace_back(
                std::move(key),
                decode_entities(tag, std::string_view(s).substr(i + 1, close - i - 1)));
            i = close + 1;
        }
        pos = i;
        m_doc.elements.push_back(std::move(e));
        return static_cast<int>(m_doc.elements.size()) - 1;
    }

    XmlDocument m_doc;
    std::size_t m_line_pos = 0;
    int m_line = 1;
};

constexpr char kBase64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

int base64_value(char c) {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
}

}  // namespace

XmlDocument parse_xml(const std::string& file) {
    return XmlParser(file, read_file_bytes(file)).parse();
}

std::string xml_escape(std::string_view text) {
    std::string out;
    for (char c : text) {
        switch (c) {
            case '&':
                out += "&amp;";
                break;
            case '<':
                out += "&lt;";
                break;
            case '>':
                out += "&gt;";
                break;
            case '"':
                out += "&quot;";
                break;
            case '\'':
                out += "&apos;";
                break;
            default:
                out += c;
        }
    }
    return out;
}

std::string base64_encode(const std::uint8_t* data, std::size_t size) {
    std::string out;
    out.reserve((size + 2) / 3 * 4);
    std::size_t i = 0;
    for (; i + 3 <= size; i += 3) {
        const std::uint32_t v = (std::uint32_t(data[i]) << 16) | (std::uint32_t(data[i + 1]) << 8) |
                                std::uint32_t(data[i + 2]);
        out += kBase64[(v >> 18) & 63];
        out += kBase64[(v >> 12) & 63];
        out += kBase64[(v >> 6) & 63];
        out += kBase64[v & 63];
    }
    if (i < size) {
        std::uint32_t v = std::uint32_t(data[i]) << 16;
        if (i + 1 < size) v |= std::uint32_t(data[i + 1]) << 8;
        out += kBase64[(v >> 18) & 63];
        out += kBase64[(v >> 12) & 63];
        out += i + 1 < size ? kBase64[(v >> 6) & 63] : '=';
        out += '=';
    }
    return out;
}

bool Base64Reader::refill() {
    int values[4];
    int count = 0, padding = 0;
    while (count < 4) {
        if (m_pos >= m_text.size()) return false;
        const char c = m_text[m_pos++];
        if (is_space(c)) continue;
        if (c == '=') {
            if (count < 2) return false;
            ++padding;
            values[count++] = 0;
            continue;
        }
        if (padding > 0) return false;  // data after padding within a group
        values[count] = base64_value(c);
        if (values[count] < 0) return false;
        ++count;
    }
    const std::uint32_t v = (std::uint32_t(values[0]) << 18) | (std::uint32_t(values[1]) << 12) |
                            (std::uint32_t(values[2]) << 6) | std::uint32_t(values[3]);
    m_buffer[0] = static_cast<std::uint8_t>(v >> 16);
    m_buffer[1] = static_cast<std::uint8_t>(v >> 8);
    m_buffer[2] = static_cast<std::uint8_t>(v);
    m_buffered = 3 - padding;
    m_next = 0;
    return true;
}

bool Base64Reader::read(std::uint8_t* out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
        if (m_next >= m_buffered && !refill()) return false;
        out[i] = m_buffer[m_next++];
    }
    return true;
}

}  // namespace coarsegrain::io::detail
