#include "io/chunk_codecs.hpp"

#include <bzlib.h>
#include <fmt/format.h>
#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <climits>
#include <memory>

namespace metro::internal {
namespace {

// Sizes the output; "" or why not.
std::string Prepare(uint64_t size, std::string* out) {
  if (size > kMaxChunkBytes) {
    return fmt::format("uncompressed size {} bytes: expected at most {} bytes per chunk", size,
                       kMaxChunkBytes);
  }
  out->resize(static_cast<size_t>(size));
  return "";
}

}  // namespace

std::string DecompressZstd(std::string_view in, uint64_t size, std::string* out) {
  if (std::string why = Prepare(size, out); !why.empty()) return why;
  const size_t got = ZSTD_decompress(out->data(), out->size(), in.data(), in.size());
  if (ZSTD_isError(got)) return fmt::format("zstd: {}", ZSTD_getErrorName(got));
  if (got != size) {
    return fmt::format("zstd: {} bytes decompressed; the chunk says {}", got, size);
  }
  return "";
}

std::string DecompressLz4Frame(std::string_view in, uint64_t size, std::string* out) {
  if (std::string why = Prepare(size, out); !why.empty()) return why;
  LZ4F_dctx* raw = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) {
    return "lz4: cannot create a decompression context";
  }
  std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> dctx(
      raw, &LZ4F_freeDecompressionContext);
  size_t in_at = 0, out_at = 0;
  size_t hint = 1;
  while (hint != 0) {
    size_t in_n = in.size() - in_at;
    size_t out_n = out->size() - out_at;
    hint = LZ4F_decompress(dctx.get(), out->data() + out_at, &out_n, in.data() + in_at, &in_n,
                           nullptr);
    if (LZ4F_isError(hint)) return fmt::format("lz4: {}", LZ4F_getErrorName(hint));
    in_at += in_n;
    out_at += out_n;
    if (hint != 0 && in_n == 0 && out_n == 0) {
      return fmt::format("lz4: the frame ends early ({} of {} bytes decompressed)", out_at, size);
    }
  }
  if (out_at != size) {
    return fmt::format("lz4: {} bytes decompressed; the chunk says {}", out_at, size);
  }
  return "";
}

std::string DecompressBz2(std::string_view in, uint64_t size, std::string* out) {
  if (std::string why = Prepare(size, out); !why.empty()) return why;
  if (in.size() > UINT_MAX) return "bz2: a compressed chunk above 4 GiB";
  unsigned int out_n = static_cast<unsigned int>(size);
  const int rc = BZ2_bzBuffToBuffDecompress(out->data(), &out_n, const_cast<char*>(in.data()),
                                            static_cast<unsigned int>(in.size()), 0, 0);
  if (rc != BZ_OK) {
    return fmt::format("bz2: error {} ({})", rc,
                       rc == BZ_OUTBUFF_FULL ? "more data than the chunk's size"
                       : rc == BZ_DATA_ERROR || rc == BZ_DATA_ERROR_MAGIC ? "corrupt data"
                       : rc == BZ_UNEXPECTED_EOF                          ? "the data ends early"
                                                                          : "libbz2");
  }
  if (out_n != size) {
    return fmt::format("bz2: {} bytes decompressed; the chunk says {}", out_n, size);
  }
  return "";
}

uint32_t Crc32(std::string_view bytes) {
  uLong crc = crc32(0L, Z_NULL, 0);
  size_t at = 0;
  while (at < bytes.size()) {
    const size_t n = std::min<size_t>(bytes.size() - at, UINT_MAX);
    crc = crc32(crc, reinterpret_cast<const Bytef*>(bytes.data() + at), static_cast<uInt>(n));
    at += n;
  }
  return static_cast<uint32_t>(crc);
}

}  // namespace metro::internal
