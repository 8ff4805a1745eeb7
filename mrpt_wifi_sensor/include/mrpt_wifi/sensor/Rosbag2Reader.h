/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

// ROS 2 bags (rosbag2) without a ROS 2 installation: MCAP files (McapReader.h), SQLite .db3
// files (Debian's libsqlite3: tables topics, messages and, since Iron, message_definitions),
// and bag directories (metadata.yaml's file list, else every .mcap/.db3 in name order).

#include <mrpt_wifi/sensor/McapReader.h>

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace mrpt_wifi::ros2
{
/** One message of a bag as stored (serialized bytes, valid during the callback). */
struct BagMessage
{
    std::string file;                 //!< the storage file it is in
    std::string topic, type;          //!< type e.g. "rf_msgs/msg/Wifi" ("" when MCAP has none)
    std::string serializationFormat;  //!< "cdr"
    /** The type's definition when the bag has one (MCAP schema, SQLite message_definitions),
     *  else nullptr: SQLite bags before Iron carry only the type name. */
    const std::string* definition = nullptr;
    std::string definitionEncoding;  //!< "ros2msg", "ros2idl", ...
    uint64_t timeNs = 0;             //!< the bag's receive time [ns since the epoch]
    const uint8_t* data = nullptr;
    size_t size = 0;
    /** MCAP: byte offset of the Message record (or of its Chunk); SQLite: the message's id. */
    uint64_t offset = 0;
    std::string where;  //!< "byte N" / "message id N" and the topic, for messages to the user
};

/** What a read went through. */
struct BagReadStats
{
    std::vector<std::string> files;              //!< storage files read, in order
    std::map<std::string, uint64_t> mcapChunks;  //!< by compression ("none", "zstd", "lz4")
    uint64_t messages = 0;                       //!< delivered
    uint64_t crcsChecked = 0;                    //!< MCAP CRCs that matched
    uint64_t mcapWithoutSummary = 0;             //!< MCAP files without a summary section
    std::string asString() const;
};

/** True for what forEachBagMessage reads: a directory holding metadata.yaml or .mcap / .db3
 *  files, or a file ending in .mcap or .db3. */
bool looksLikeRosbag2(const std::string& path);

/** The storage files of a bag (a directory: metadata.yaml's relative_file_paths, else every
 *  .mcap / .db3 in name order; a file: itself). Throws std::runtime_error naming the path when
 *  there are none, or when metadata.yaml says the files are compressed as a whole. */
std::vector<std::string> bagFiles(const std::string& path);

/** Calls `onMessage` for every message of the bag, file by file in stored order (MCAP: file
 *  order; SQLite: by timestamp). Messages a bag compressed one by one (metadata.yaml
 *  compression_mode MESSAGE, zstd) are decompressed. Throws std::runtime_error naming the file
 *  and byte offset (MCAP) or message id (SQLite) on a corrupt or truncated file, after
 *  delivering every message before the fault. */
void forEachBagMessage(
    const std::string& path, const std::function<void(const BagMessage&)>& onMessage,
    const std::function<void(double)>& onProgress = {}, BagReadStats* stats = nullptr);

/** The MCAP part of forEachBagMessage on bytes in memory (the fuzz target's entry). */
void forEachMcapBagMessage(
    const uint8_t* data, size_t len, const std::string& name,
    const std::function<void(const BagMessage&)>& onMessage, BagReadStats* stats = nullptr,
    const mcap::McapReadOptions& options = {});

}  // namespace mrpt_wifi::ros2
