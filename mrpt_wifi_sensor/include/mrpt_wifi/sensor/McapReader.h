/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

// Reading MCAP files (https://mcap.dev/spec, major version 0), this project's own code from the
// specification: the data section read linearly record by record (a summary section is not
// needed and not trusted), chunks uncompressed or compressed with zstd (libzstd) or lz4 frames
// (liblz4), every CRC checked where the writer filled it in (zlib's crc32).

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace mrpt_wifi::mcap
{
struct Schema
{
    uint16_t id = 0;
    std::string name, encoding;  //!< e.g. "rf_msgs/msg/Wifi", "ros2msg"
    std::vector<uint8_t> data;   //!< the definition (ros2msg: text)
};

struct Channel
{
    uint16_t id = 0, schemaId = 0;  //!< schemaId 0: no schema
    std::string topic, messageEncoding;
    std::map<std::string, std::string> metadata;
};

/** One message as the reader hands it over; the pointers are valid during the callback. */
struct MessageView
{
    const Channel* channel = nullptr;
    const Schema* schema = nullptr;  //!< nullptr: the channel has none, or an unknown id
    uint32_t sequence = 0;
    uint64_t logTime = 0, publishTime = 0;  //!< ns since the epoch (rosbag2: receive time)
    const uint8_t* data = nullptr;
    size_t size = 0;
    /** Byte offset of the Message record in the file, or of the Chunk record holding it. */
    uint64_t fileOffset = 0;
    /** Inside a chunk: byte offset of the record in the chunk's uncompressed records, else 0. */
    uint64_t chunkOffset = 0;
    bool inChunk = false;
};

/** A corrupt or truncated file: what, and the byte offset where it was found. */
class McapError : public std::runtime_error
{
public:
    McapError(const std::string& name, uint64_t offset, const std::string& what);
    uint64_t offset = 0;
};

struct McapReadOptions
{
    /** A chunk claiming more uncompressed bytes than this is refused as corrupt (nothing is
     *  allocated for it); writers use 1–10 MiB. */
    uint64_t maxChunkBytes = uint64_t(1) << 30;
};

struct McapReadStats
{
    uint64_t records = 0;                                 //!< top-level records
    uint64_t chunks = 0;                                  //!< by compression: counted below
    uint64_t messages = 0;                                //!< delivered
    std::map<std::string, uint64_t> chunksByCompression;  //!< "" = uncompressed
    uint64_t crcsChecked = 0;  //!< chunk, data section, summary, attachment CRCs that matched
    bool hasDataEnd = false, hasFooter = false, hasSummary = false;
    std::string profile, library;  //!< from the Header record
};

/** Where the reader gets its bytes: a file or memory. */
class ByteSource
{
public:
    virtual ~ByteSource() = default;
    virtual uint64_t size() const = 0;
    /** Reads exactly n bytes at offset (the caller keeps within size()). */
    virtual void read(uint64_t offset, size_t n, uint8_t* out) = 0;
    /** The file name, for errors. */
    virtual const std::string& name() const = 0;
};
std::unique_ptr<ByteSource> openFileSource(const std::string& path);
std::unique_ptr<ByteSource> memorySource(const uint8_t* data, size_t len, const std::string& name);

/** True if the bytes start with MCAP's magic ("\x89MCAP0\r\n"). */
bool hasMcapMagic(const uint8_t* head, size_t len);

/** Calls `onMessage` for every message in file order. Throws McapError naming the source and
 *  the byte offset on a corrupt or truncated file, after delivering every message before the
 *  fault; `stats` (if given) is filled either way. `onProgress(fraction)` now and then. */
void readMcap(
    ByteSource& source, const std::function<void(const MessageView&)>& onMessage,
    const std::function<void(double)>& onProgress = {}, McapReadStats* stats = nullptr,
    const McapReadOptions& options = {});

}  // namespace mrpt_wifi::mcap
