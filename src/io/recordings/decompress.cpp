#include "io/recordings/decompress.h"

#include "core/types.h"

#include <bzlib.h>
#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <memory>

namespace vkmesh::io::recording::detail {

namespace {

// The output buffer: starts small and doubles as the decompressor fills it, up to expectedSize + 1 (the extra
// byte lets a stream that produces more than declared be caught rather than cut silently).
class Output {
public:
    Output(uint64_t expected, size_t inSize) : cap_(expected + 1) {
        buf_.resize(static_cast<size_t>(std::min<uint64_t>(cap_, std::max<uint64_t>(uint64_t(inSize) * 4, 1 << 16))));
    }
    // Room to write into: grows when full; null when the cap is reached.
    uint8_t* room(size_t& n) {
        if (used_ == buf_.size()) {
            if (buf_.size() >= cap_) {
                n = 0;
                return nullptr;
            }
            buf_.resize(static_cast<size_t>(std::min<uint64_t>(cap_, uint64_t(buf_.size()) * 2)));
        }
        n = buf_.size() - used_;
        return buf_.data() + used_;
    }
    void produced(size_t n) { used_ += n; }
    size_t used() const { return used_; }
    std::vector<uint8_t> take() {
        buf_.resize(used_);
        return std::move(buf_);
    }

private:
    uint64_t cap_;
    std::vector<uint8_t> buf_;
    size_t used_ = 0;
};

std::vector<uint8_t> finish(Output& out, bool ended, size_t inLeft, uint64_t expected, const std::string& what,
                            const std::string& where) {
    if (out.used() > expected)
        throw Error(where + ": " + what + " data decompresses to more than the " + std::to_string(expected) +
                    " bytes the chunk declares");
    if (!ended) throw Error(where + ": " + what + " data is truncated (the compressed stream does not end)");
    if (inLeft != 0)
        throw Error(where + ": " + std::to_string(inLeft) + " bytes follow the end of the " + what + " stream");
    if (out.used() != expected)
        throw Error(where + ": " + what + " data decompresses to " + std::to_string(out.used()) + " bytes, the chunk declares " +
                    std::to_string(expected));
    return out.take();
}

std::vector<uint8_t> bz2(std::string_view in, uint64_t expected, const std::string& where) {
    // The streaming API rather than BZ2_bzBuffToBuffDecompress: that one needs the whole output buffer up front.
    bz_stream s{};
    if (BZ2_bzDecompressInit(&s, 0, 0) != BZ_OK) throw Error(where + ": cannot start bz2 decompression");
    std::unique_ptr<bz_stream, void (*)(bz_stream*)> guard(&s, [](bz_stream* p) { BZ2_bzDecompressEnd(p); });
    Output out(expected, in.size());
    s.next_in = const_cast<char*>(in.data());  // bzlib's API is not const-correct; it does not write the input
    size_t inLeft = in.size();
    bool ended = false;
    for (;;) {
        // avail_in is an unsigned int: feed at most 1 GiB at a time.
        unsigned feed = static_cast<unsigned>(std::min<size_t>(inLeft, 1u << 30));
        s.avail_in = feed;
        size_t n = 0;
        uint8_t* dst = out.room(n);
        if (!dst) break;
        s.next_out = reinterpret_cast<char*>(dst);
        s.avail_out = static_cast<unsigned>(std::min<size_t>(n, 1u << 30));
        unsigned outBefore = s.avail_out;
        int rc = BZ2_bzDecompress(&s);
        inLeft -= feed - s.avail_in;
        out.produced(outBefore - s.avail_out);
        if (rc == BZ_STREAM_END) {
            ended = true;
            break;
        }
        if (rc != BZ_OK) throw Error(where + ": corrupt bz2 data (bzlib error " + std::to_string(rc) + ")");
        if (inLeft == 0 && s.avail_out != 0) break;  // all input consumed, stream not ended: truncated
    }
    return finish(out, ended, inLeft, expected, "bz2", where);
}

std::vector<uint8_t> lz4(std::string_view in, uint64_t expected, const std::string& where) {
    LZ4F_dctx* ctx = nullptr;
    if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION)))
        throw Error(where + ": cannot start lz4 decompression");
    std::unique_ptr<LZ4F_dctx, LZ4F_errorCode_t (*)(LZ4F_dctx*)> guard(ctx, LZ4F_freeDecompressionContext);
    Output out(expected, in.size());
    const char* src = in.data();
    size_t inLeft = in.size();
    bool ended = false;
    for (;;) {
        size_t n = 0;
        uint8_t* dst = out.room(n);
        if (!dst) break;
        size_t srcSize = inLeft, dstSize = n;
        size_t hint = LZ4F_decompress(ctx, dst, &dstSize, src, &srcSize, nullptr);
        if (LZ4F_isError(hint))
            throw Error(where + ": corrupt lz4 data (" + LZ4F_getErrorName(hint) + ")");
        src += srcSize;
        inLeft -= srcSize;
        out.produced(dstSize);
        if (hint == 0) {  // the frame is complete
            ended = true;
            break;
        }
        if (srcSize == 0 && dstSize == 0) break;  // no progress: wants input that is not there (truncated)
    }
    return finish(out, ended, inLeft, expected, "lz4", where);
}

std::vector<uint8_t> zstd(std::string_view in, uint64_t expected, const std::string& where) {
    ZSTD_DCtx* ctx = ZSTD_createDCtx();
    if (!ctx) throw Error(where + ": cannot start zstd decompression");
    std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> guard(ctx, ZSTD_freeDCtx);
    Output out(expected, in.size());
    ZSTD_inBuffer src{in.data(), in.size(), 0};
    bool ended = false;
    for (;;) {
        size_t n = 0;
        uint8_t* dst = out.room(n);
        if (!dst) break;
        ZSTD_outBuffer o{dst, n, 0};
        size_t before = src.pos;
        size_t rc = ZSTD_decompressStream(ctx, &o, &src);
        if (ZSTD_isError(rc)) throw Error(where + ": corrupt zstd data (" + ZSTD_getErrorName(rc) + ")");
        out.produced(o.pos);
        if (rc == 0) {  // a frame is complete (MCAP chunks hold one)
            ended = true;
            break;
        }
        if (src.pos == before && o.pos == 0) break;  // no progress: wants input that is not there (truncated)
    }
    return finish(out, ended, in.size() - src.pos, expected, "zstd", where);
}

}  // namespace

std::vector<uint8_t> decompress(std::string_view compression, std::string_view in, uint64_t expectedSize,
                                const std::string& where) {
    if (expectedSize > maxChunkBytes())
        throw Error(where + ": the chunk declares " + std::to_string(expectedSize) +
                    " bytes uncompressed, more than the limit of " + std::to_string(maxChunkBytes()));
    if (compression.empty() || compression == "none") {
        if (in.size() != expectedSize)
            throw Error(where + ": an uncompressed chunk of " + std::to_string(in.size()) + " bytes declares " +
                        std::to_string(expectedSize));
        return std::vector<uint8_t>(in.begin(), in.end());
    }
    if (compression == "bz2") return bz2(in, expectedSize, where);
    if (compression == "lz4") return lz4(in, expectedSize, where);
    if (compression == "zstd") return zstd(in, expectedSize, where);
    throw Error(where + ": unknown compression '" + std::string(compression) +
                "' (vkmesh reads none, bz2, lz4 and zstd)");
}

}  // namespace vkmesh::io::recording::detail
