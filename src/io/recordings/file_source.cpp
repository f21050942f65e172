#include "io/recordings/file_source.h"

#include "core/types.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace vkmesh::io::recording::detail {

ByteSource ByteSource::openFile(const std::filesystem::path& path) {
    ByteSource s;
    s.name_ = path.string();
    s.fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (s.fd_ < 0) throw Error(s.name_ + ": cannot open: " + std::strerror(errno));
    struct stat st {};
    if (::fstat(s.fd_, &st) != 0) throw Error(s.name_ + ": cannot stat: " + std::strerror(errno));
    if (!S_ISREG(st.st_mode)) throw Error(s.name_ + ": not a regular file");
    s.size_ = static_cast<uint64_t>(st.st_size);
    return s;
}

ByteSource ByteSource::fromBytes(std::string_view bytes) {
    ByteSource s;
    s.memory_.assign(bytes);
    s.size_ = s.memory_.size();
    return s;
}

ByteSource::ByteSource(ByteSource&& o) noexcept
    : fd_(o.fd_), memory_(std::move(o.memory_)), name_(std::move(o.name_)), size_(o.size_) {
    o.fd_ = -1;
}

ByteSource::~ByteSource() {
    if (fd_ >= 0) ::close(fd_);
}

std::string ByteSource::read(uint64_t offset, uint64_t n, const std::string& where) const {
    if (offset > size_ || n > size_ - offset)
        throw Error(where + ": bytes " + std::to_string(offset) + "+" + std::to_string(n) + " lie past the end (" +
                    std::to_string(size_) + " bytes)");
    if (fd_ < 0) return memory_.substr(static_cast<size_t>(offset), static_cast<size_t>(n));
    std::string out(static_cast<size_t>(n), '\0');
    size_t done = 0;
    while (done < n) {
        ssize_t r = ::pread(fd_, out.data() + done, n - done, static_cast<off_t>(offset + done));
        if (r < 0 && errno == EINTR) continue;
        if (r < 0) throw Error(where + ": read error: " + std::strerror(errno));
        // The file shrank since it was opened (a recording being rewritten).
        if (r == 0) throw Error(where + ": the file ended early (was it truncated while open?)");
        done += static_cast<size_t>(r);
    }
    return out;
}

}  // namespace vkmesh::io::recording::detail
