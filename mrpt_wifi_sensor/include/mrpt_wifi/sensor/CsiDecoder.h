/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/sensor/CsiFrameAssembler.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace mrpt_wifi
{
/** Options every decoder may use (each takes what applies to its format). */
struct CsiDecodeOptions
{
    CsiFrameAssemblerOptions assembler;          //!< Nexmon captures; label and pose for all
    uint16_t udpPort = nexmon::kDefaultUdpPort;  //!< Nexmon captures (0: any port)
    /** Channel for formats whose records don't carry one (Intel 5300 .dat). When unset the
     *  decoder assumes one and says so in the summary notes. */
    std::optional<Chanspec> chanspec;
    /** ESP32 lines: keep the L-LTF even when the line also has an HT-LTF (by default the
     *  HT-LTF, and with STBC the second space-time stream's, is what the frame holds). */
    bool esp32LegacyLtf = false;
    /** A malformed record stops the decode (CsiDecodeError) instead of being skipped and
     *  counted in CsiDecodeSummary::rejected (`--strict` of the CLIs). */
    bool strict = false;
};

/** Malformed records of one kind that a decode skipped (CsiDecodeOptions::strict off). */
struct CsiRejectedRecords
{
    std::string reason;        //!< what was wrong, the same text for every record counted here
    uint64_t count = 0;        //!< how many records
    uint64_t firstOffset = 0;  //!< byte offset of the first (a line format: also its line)
    std::string firstWhere;    //!< "byte N" or "line N" of the first
};

/** What a decode went through. */
struct CsiDecodeSummary
{
    std::string format;              //!< decoder name
    uint64_t records = 0;            //!< records / datagrams / lines / objects read
    uint64_t skipped = 0;            //!< records of the format that carry no CSI (skipped, counted)
    uint64_t frames = 0;             //!< CSI frames delivered
    std::string details;             //!< format-specific counters, one line each
    std::vector<std::string> notes;  //!< assumptions the decoder made (e.g. a channel)
    /** Malformed records skipped, by reason (empty with CsiDecodeOptions::strict: the first
     *  one throws). A truncated last record (a capture that was killed) is a note instead. */
    std::vector<CsiRejectedRecords> rejected;
    /** Records in `rejected`, all reasons. */
    uint64_t rejectedRecords() const;
    /** Adds a note once (the same text again is not repeated). */
    void noteOnce(const std::string& note);
    std::string asString() const;
};

/** A malformed input: names the file, the byte offset of the bad record and the format. Every
 * frame before the fault has been delivered when this is thrown. */
class CsiDecodeError : public std::runtime_error
{
public:
    CsiDecodeError(
        const std::string& path, uint64_t offset, const std::string& format,
        const std::string& what);
    std::string path;
    uint64_t offset = 0;
    std::string format;
};

/** A malformed record at `offset` (`where`: "byte N", or "line N" for line formats): with
 *  options.strict throws CsiDecodeError, else counts it in summary.rejected under `reason`
 *  (detail: this record's particulars, shown for the first of each reason) so the decoder can
 *  go on with the next record. */
void rejectRecord(
    const std::string& path, const std::string& format, const CsiDecodeOptions& options,
    CsiDecodeSummary& summary, uint64_t offset, const std::string& reason,
    const std::string& detail = {}, const std::string& where = {});

/** Help text of the converters' `--strict` switch (the same in every program). */
extern const char* const kStrictOptionHelp;
/** A converter's exit status for a decode that ended without error (`rc` 0) or with one (`rc`
 *  1, returned as is): cli::kExitRecordsSkipped, with one line on stderr, when malformed
 *  records were skipped; 0 otherwise. */
int conversionExitStatus(int rc, const CsiDecodeSummary& summary, const std::string& program);

using CsiFrameSink = std::function<void(CObservationWiFiCSI::Ptr&&)>;
using CsiProgress = std::function<void(double)>;

/** One CSI source format: recognises its files by content and turns them into
 * CObservationWiFiCSI frames. A new format is one class registered with
 * MRPT_WIFI_REGISTER_CSI_DECODER in its own .cpp file, plus its tests. */
class CsiDecoder
{
public:
    virtual ~CsiDecoder() = default;
    /** Name for --format and the summary, e.g. "nexmon", "intel5300", "esp32", "rawlog". */
    virtual std::string name() const = 0;
    /** One line for --help: the radios and file kinds. */
    virtual std::string description() const = 0;
    /** How sure the decoder is that a file starting with `head` (up to 4 KiB) is its format:
     *  0 = not mine, 100 = a magic number matched. */
    virtual int probe(const uint8_t* head, size_t len) const = 0;
    /** Decodes the whole file in order. A malformed record is skipped and counted
     *  (rejectRecord), or with options.strict throws CsiDecodeError after delivering
     *  everything before it; content that can't be resynchronised after (a broken file header,
     *  a length field that loses the record boundaries) throws either way. `summary` is filled
     *  either way. */
    virtual void decodeFile(
        const std::string& path, const CsiDecodeOptions& options, const CsiFrameSink& onFrame,
        const CsiProgress& onProgress, CsiDecodeSummary& summary) const = 0;
};

/** Every decoder linked into the program, by name. */
class CsiDecoderRegistry
{
public:
    static CsiDecoderRegistry& instance();
    void add(std::shared_ptr<const CsiDecoder> decoder);
    /** nullptr if no decoder has that name. */
    std::shared_ptr<const CsiDecoder> find(const std::string& name) const;
    /** The decoders, sorted by name. */
    std::vector<std::shared_ptr<const CsiDecoder>> all() const;
    /** "esp32|intel5300|nexmon|rawlog" for help texts. */
    std::string names(const std::string& separator = "|") const;
    /** The decoder whose probe is highest for the file's first bytes. Throws
     *  std::runtime_error naming the file if it can't be read, is empty, or no decoder
     *  recognises it. */
    std::shared_ptr<const CsiDecoder> detect(const std::string& path) const;

private:
    std::vector<std::shared_ptr<const CsiDecoder>> decoders_;
};

/** Registers a decoder class at library load. */
#define MRPT_WIFI_REGISTER_CSI_DECODER(ClassName)                                       \
    namespace                                                                           \
    {                                                                                   \
    const bool registered_##ClassName = []                                              \
    {                                                                                   \
        ::mrpt_wifi::CsiDecoderRegistry::instance().add(std::make_shared<ClassName>()); \
        return true;                                                                    \
    }();                                                                                \
    }

/** Decodes a file with the named decoder, or the detected one when `format` is empty or
 * "auto". Returns the decoder used. */
std::shared_ptr<const CsiDecoder> decodeCsiFile(
    const std::string& path, const std::string& format, const CsiDecodeOptions& options,
    const CsiFrameSink& onFrame, const CsiProgress& onProgress = {},
    CsiDecodeSummary* summary = nullptr);

/** Applies a CLI's `--format VALUE`: a decoder name, "auto", or one of the Nexmon header
 * variants (nexmon-legacy, ubilocate; "nexmon" also forces the current header), which select
 * the nexmon decoder with that header. Returns the decoder name for decodeCsiFile ("auto" or
 * a name); throws std::invalid_argument listing the choices. */
std::string applyFormatOption(const std::string& value, CsiDecodeOptions& options);
/** "auto|esp32|intel5300|nexmon|nexmon-legacy|rawlog|ubilocate" for help texts. */
std::string formatOptionChoices();

/** Reads a whole file into memory; throws std::runtime_error naming it. */
std::vector<uint8_t> readWholeFile(const std::string& path);

/** Calls a progress callback only when the fraction moved by 1 % (or reached 1). */
class ProgressThrottle
{
public:
    explicit ProgressThrottle(const CsiProgress& f) : f_(f) {}
    void update(uint64_t done, uint64_t total);

private:
    const CsiProgress& f_;
    double last_ = -1.0;
};

}  // namespace mrpt_wifi
