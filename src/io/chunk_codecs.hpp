// Private: the chunk codecs of MCAP and ROS 1 bags, through Debian's libraries (libzstd,
// liblz4's frame API, libbz2). Each decompresses `in` into `out`, which must come out at
// exactly `size` bytes; returns "" or what is wrong ("zstd: ...").
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace metro::internal {

// The largest uncompressed chunk metro accepts (recorders write 768 KiB to 4 MiB chunks).
constexpr uint64_t kMaxChunkBytes = uint64_t{256} << 20;

std::string DecompressZstd(std::string_view in, uint64_t size, std::string* out);
// The LZ4 frame format (lz4.org "LZ4 Frame Format Description"): MCAP's "lz4" and ROS 1's
// roslz4 both write it.
std::string DecompressLz4Frame(std::string_view in, uint64_t size, std::string* out);
std::string DecompressBz2(std::string_view in, uint64_t size, std::string* out);

// CRC-32 (ISO-HDLC, as zlib and MCAP compute it) of `bytes`.
uint32_t Crc32(std::string_view bytes);

}  // namespace metro::internal
