// Internal to src/io/recordings: bounded little-endian reading of container records. Every read checks the
// bytes are there first and throws vkmesh::Error "<where>: truncated ..." otherwise, so that a parser never
// reads past its buffer whatever a file's lengths say.
#pragma once

#include "core/types.h"

#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

namespace vkmesh::io::recording::detail {

class ByteReader {
public:
    // `where` names the record for error messages; kept by reference (callers hold it for the reader's life).
    ByteReader(std::string_view bytes, const std::string& where) : bytes_(bytes), where_(where) {}

    size_t pos() const { return pos_; }
    size_t remaining() const { return bytes_.size() - pos_; }
    bool atEnd() const { return pos_ == bytes_.size(); }

    void need(uint64_t n, const char* what) const {
        if (n > remaining())
            throw Error(where_ + ": truncated: " + what + " needs " + std::to_string(n) + " bytes at offset " +
                        std::to_string(pos_) + ", " + std::to_string(remaining()) + " left");
    }
    std::string_view take(uint64_t n, const char* what) {
        need(n, what);
        std::string_view v = bytes_.substr(pos_, static_cast<size_t>(n));
        pos_ += static_cast<size_t>(n);
        return v;
    }
    template <typename T>
    T le(const char* what) {
        static_assert(std::is_integral_v<T>);
        std::string_view b = take(sizeof(T), what);
        T v = 0;
        for (size_t i = 0; i < sizeof(T); ++i) v |= static_cast<T>(static_cast<T>(static_cast<uint8_t>(b[i])) << (8 * i));
        return v;
    }
    uint8_t u8(const char* what) { return le<uint8_t>(what); }
    uint16_t u16(const char* what) { return le<uint16_t>(what); }
    uint32_t u32(const char* what) { return le<uint32_t>(what); }
    uint64_t u64(const char* what) { return le<uint64_t>(what); }

private:
    std::string_view bytes_;
    const std::string& where_;
    size_t pos_ = 0;
};

}  // namespace vkmesh::io::recording::detail
