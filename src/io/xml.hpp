#pragma once
/// @file Internal: a small XML reader for VTK XML files (elements, attributes, content ranges,
/// comments, processing instructions) and the base64 coding VTK uses for binary data.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace coarsegrain::io::detail {

/// One XML element. Content is the raw text between its start and end tags.
struct XmlElement {
    std::string name;
    std::vector<std::pair<std::string, std::string>> attributes;  ///< entity-decoded values
    std::vector<int> children;  ///< indices into XmlDocument::elements
    std::size_t content_begin = 0;
    std::size_t content_end = 0;
    int line = 0;  ///< line of the start tag

    /// Value of an attribute, or nullptr.
    const std::string* attribute(std::string_view key) const;
};

/// A parsed document. The <AppendedData> element's content is kept raw (it may be binary):
/// it runs from after the '_' marker to the last "</AppendedData>" of the file.
struct XmlDocument {
    std::string file;
    std::string text;
    std::vector<XmlElement> elements;  ///< elements[0] is the root

    /// Children of `parent` named `name`.
    std::vector<const XmlElement*> children(const XmlElement& parent, std::string_view name) const;
    std::string_view content(const XmlElement& e) const {
        return std::string_view(text).substr(e.content_begin, e.content_end - e.content_begin);
    }
};

/// Parses the file. @throws MeshReadError "FILE:LINE: ..." for malformed XML
XmlDocument parse_xml(const std::string& file);

/// Escapes & < > " ' for an attribute value.
std::string xml_escape(std::string_view text);

/// Standard base64 with '=' padding.
std::string base64_encode(const std::uint8_t* data, std::size_t size);

/// Decodes base64 text incrementally, skipping whitespace. Padding may end any 4-character
/// group, so separately encoded blocks (a VTK header, then its data) decode as one stream.
class Base64Reader {
  public:
    explicit Base64Reader(std::string_view text) : m_text(text) {}
    /// Decodes the next n bytes into out; false if the text ends first or is not base64.
    bool read(std::uint8_t* out, std::size_t n);
    /// Upper bound on the bytes still decodable.
    std::size_t bytes_left() const { return (m_text.size() - m_pos) / 4 * 3 + 3; }

  private:
    bool refill();
    std::string_view m_text;
    std::size_t m_pos = 0;
    std::uint8_t m_buffer[3] = {0, 0, 0};
    int m_buffered = 0;
    int m_next = 0;
};

}  // namespace coarsegrain::io::detail
