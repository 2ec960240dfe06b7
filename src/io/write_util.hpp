#pragma once
/// @file Internal: helpers shared by the mesh writers.
#include <fmt/format.h>

#include <ostream>
#include <string>

#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::io::detail {

/// Checks what a writer relies on: sizes consistent with the element type and node indices in
/// range (not element orientation: a writer writes what it is given).
/// @throws Error naming the file and the inconsistency
void check_writable(const mesh::Mesh& mesh, const std::string& file);

/// Appends text to a buffer and hands it to the stream in large pieces.
class BufferedWriter {
  public:
    explicit BufferedWriter(std::ostream& out) : m_out(out) {}
    ~BufferedWriter() { flush(); }
    BufferedWriter(const BufferedWriter&) = delete;
    BufferedWriter& operator=(const BufferedWriter&) = delete;

    template <class... Args>
    void print(fmt::format_string<Args...> format, Args&&... args) {
        fmt::format_to(std::back_inserter(m_buffer), format, std::forward<Args>(args)...);
        if (m_buffer.size() > (1u << 20)) flush();
    }
    void flush() {
        m_out.write(m_buffer.data(), static_cast<std::streamsize>(m_buffer.size()));
        m_buffer.clear();
    }

  private:
    std::ostream& m_out;
    fmt::memory_buffer m_buffer;
};

}  // namespace coarsegrain::io::detail
