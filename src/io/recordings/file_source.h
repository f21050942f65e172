// Internal to src/io/recordings: the bytes of a container, either a file read with pread (positioned reads
// share no file offset, so reads from several threads need no lock) or a copy in memory (openRos1Bag and
// openMcap on bytes).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace vkmesh::io::recording::detail {

class ByteSource {
public:
    static ByteSource openFile(const std::filesystem::path& path);  // throws Error naming the file
    static ByteSource fromBytes(std::string_view bytes);
    ByteSource(ByteSource&& other) noexcept;
    ByteSource& operator=(ByteSource&&) = delete;
    ByteSource(const ByteSource&) = delete;
    ~ByteSource();

    uint64_t size() const { return size_; }
    // Bytes [offset, offset + n), which the caller has checked lie inside size(). Throws Error on a read error
    // (`where` names the record).
    std::string read(uint64_t offset, uint64_t n, const std::string& where) const;

private:
    ByteSource() = default;
    int fd_ = -1;
    std::string memory_;
    std::string name_;
    uint64_t size_ = 0;
};

}  // namespace vkmesh::io::recording::detail
