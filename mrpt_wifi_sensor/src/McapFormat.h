/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

// What McapReader.cpp and McapWriter.cpp share of the MCAP specification (mcap.dev/spec): the
// magic, the record opcodes, and the CRC32 the specification uses (zlib's).

#include <zlib.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>

namespace mrpt_wifi::mcap::format
{
/** Starts and ends every file (major version '0'). */
constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
/** A record is <opcode uint8><content length uint64><content>. */
constexpr size_t kRecordPrefix = 1 + 8;

enum Opcode : uint8_t
{
    kHeader = 0x01,
    kFooter = 0x02,
    kSchema = 0x03,
    kChannel = 0x04,
    kMessage = 0x05,
    kChunk = 0x06,
    kMessageIndex = 0x07,
    kChunkIndex = 0x08,
    kAttachment = 0x09,
    kAttachmentIndex = 0x0A,
    kStatistics = 0x0B,
    kMetadata = 0x0C,
    kMetadataIndex = 0x0D,
    kSummaryOffset = 0x0E,
    kDataEnd = 0x0F
};

/** CRC32 (zlib's) of `data` continued from `crc` (start from 0). */
inline uint32_t crc32Update(uint32_t crc, const uint8_t* data, size_t n)
{
    // zlib's length is an unsigned int: large buffers go in pieces.
    while (n > 0)
    {
        const size_t piece = std::min<size_t>(n, size_t(1) << 30);
        crc = uint32_t(::crc32(crc, data, uInt(piece)));
        data += piece, n -= piece;
    }
    return crc;
}
}  // namespace mrpt_wifi::mcap::format
