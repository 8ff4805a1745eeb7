/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * csi-export: writes the CSI frames of a capture or rawlog as JSON Lines, one object per
 * frame, for Python/MATLAB users. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/obs/RawlogReader.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>
#if MRPT_WIFI_HAVE_ROSBAG
#include <mrpt_wifi/sensor/RosBag.h>
#endif
#include <mrpt_wifi/sensor/CsiFileReader.h>
#include <mrpt_wifi/sensor/McapWriter.h>
#include <mrpt_wifi/sensor/Ros2Messages.h>
#include <mrpt_wifi/sensor/Ros2StandardMessages.h>

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <map>
#include <memory>

using namespace mrpt_wifi;

namespace
{
/** One JSON object per frame; floats with 9 significant digits round-trip exactly. */
void writeJsonLine(std::FILE* f, const CObservationWiFiCSI& o)
{
    std::fprintf(
        f,
        "{\"timestamp\":%.6f,\"seq\":%u,\"frag\":%u,\"mac\":\"%s\",\"rssi\":%d,"
        "\"chanspec\":%u,\"channel\":%u,\"bw\":%u,\"nfft\":%u,\"chip\":%u,\"n_rx\":%u,"
        "\"n_tx\":%u,\"present\":[",
        mrpt::Clock::toDouble(o.timestamp), o.sequenceNumber, o.fragmentNumber,
        o.transmitter.asString().c_str(), int(o.rssi_dBm), o.chanspec.raw, o.chanspec.centerChannel,
        o.chanspec.bandwidthMHz, o.nfft(), o.chipId, o.nRx, o.nTx);
    for (unsigned tx = 0; tx < o.nTx; ++tx)
    {
        std::fputs(tx ? ",[" : "[", f);
        for (unsigned rx = 0; rx < o.nRx; ++rx)
            std::fprintf(f, "%s%s", rx ? "," : "", o.isPresent(tx, rx) ? "true" : "false");
        std::fputc(']', f);
    }
    std::fprintf(f, "],\"source\":\"%s\",\"subcarriers\":[", o.source.c_str());
    const auto ks = o.dataSubcarriers();
    for (size_t i = 0; i < ks.size(); ++i) std::fprintf(f, "%s%d", i ? "," : "", ks[i]);
    std::fputs("],\"rssi_antennas\":[", f);
    for (size_t i = 0; i < o.antennaRssi_dB.size(); ++i)
        std::fprintf(f, "%s%.9g", i ? "," : "", o.antennaRssi_dB[i]);
    std::fputc(']', f);
    // Which receive core each rx row is (a router with only some cores enabled): always given,
    // so a reader never has to guess.
    std::fputs(",\"rx_cores\":[", f);
    for (unsigned rx = 0; rx < o.nRx; ++rx) std::fprintf(f, "%s%u", rx ? "," : "", o.coreOfRow(rx));
    std::fputc(']', f);
    if (!std::isnan(o.noiseFloor_dBm)) std::fprintf(f, ",\"noise_floor\":%.9g", o.noiseFloor_dBm);
    if (!std::isnan(o.agc_dB)) std::fprintf(f, ",\"agc\":%.9g", o.agc_dB);
    if (o.scaledCsiFactor != 0.0) std::fprintf(f, ",\"csi_scale\":%.17g", o.scaledCsiFactor);
    std::fputs(",\"csi\":[", f);
    for (unsigned tx = 0; tx < o.nTx; ++tx)
    {
        std::fputs(tx ? ",[" : "[", f);
        for (unsigned rx = 0; rx < o.nRx; ++rx)
        {
            std::fputs(rx ? ",[" : "[", f);
            const auto* h = o.pair(tx, rx);
            for (unsigned b = 0; b < o.nfft(); ++b)
                std::fprintf(f, "%s[%.9g,%.9g]", b ? "," : "", h[b].real(), h[b].imag());
            std::fputc(']', f);
        }
        std::fputc(']', f);
    }
    std::fputs("]}\n", f);
}
/** What --bag and --mcap export: the CSI frames of IN and, from a rawlog (csi-bearings'
 *  output), its bearings, in file order. */
struct ExportedMessages
{
    int rc = 0;  //!< 1 after a fault (named on stderr; what came before it was exported)
    uint64_t csi = 0, bearings = 0;
    CsiDecodeSummary summary;
};

ExportedMessages forEachExportedMessage(
    const std::string& in, const std::string& format, const CsiDecodeOptions& options,
    bool showProgress, const std::function<void(const CObservationWiFiCSI&)>& onCsi,
    const std::function<void(const CObservationWiFiBearing&)>& onBearing)
{
    ExportedMessages r;
    const auto counts = [&]
    { return std::to_string(r.csi) + " CSI, " + std::to_string(r.bearings) + " bearings"; };
    cli::Progress progress("csi-export", showProgress);
    const auto onProgress = [&](double f) { progress.update(f, counts()); };
    try
    {
        const auto decoder = format == "auto" ? CsiDecoderRegistry::instance().detect(in)
                                              : CsiDecoderRegistry::instance().find(format);
        if (decoder && decoder->name() == "rawlog")
        {
            r.summary.format = "rawlog";
            r.summary.records = forEachRawlogObservation(
                in,
                [&](const mrpt::obs::CObservation::Ptr& o)
                {
                    if (auto c = std::dynamic_pointer_cast<CObservationWiFiCSI>(o))
                        onCsi(*c), ++r.csi, ++r.summary.frames;
                    else if (auto b = std::dynamic_pointer_cast<CObservationWiFiBearing>(o))
                        onBearing(*b), ++r.bearings;
                },
                onProgress);
        }
        else
            decodeCsiFile(
                in, format, options,
                [&](CObservationWiFiCSI::Ptr&& o)
                {
                    onCsi(*o);
                    ++r.csi;
                },
                onProgress, &r.summary);
        progress.done(counts());
    }
    catch (const std::exception& e)
    {
        std::cerr << "\ncsi-export: error: " << e.what() << "\n";
        r.rc = 1;
    }
    return r;
}

/** The rx_id of a frame's messages: --rx-id, else the router's address, else the sensor label. */
std::string receiverId(const CObservationWiFiCSI& o, const std::string& rxId)
{
    return !rxId.empty() ? rxId : !o.routerAddress.empty() ? o.routerAddress : o.sensorLabel;
}

/** --bag: CSI (and a rawlog's bearings) as WiROS's messages. */
int exportBag(
    const std::string& in, const std::string& format, const CsiDecodeOptions& options,
    const std::string& out, const std::string& rxId, bool showProgress)
{
#if MRPT_WIFI_HAVE_ROSBAG
    ros1::BagWriter bag(out);
    const auto r = forEachExportedMessage(
        in, format, options, showProgress,
        [&](const CObservationWiFiCSI& o)
        {
            bag.write(
                "/csi", mrpt::Clock::toDouble(o.timestamp), ros1::wifiType(),
                ros1::serialize(ros1::fromObservation(o, receiverId(o, rxId))));
        },
        [&](const CObservationWiFiBearing& b)
        {
            bag.write(
                "/bearing", mrpt::Clock::toDouble(b.timestamp), ros1::bearingType(),
                ros1::serialize(ros1::fromBearing(b)));
        });
    bag.close();
    std::cerr << r.summary.asString() << "\n"
              << "Output: " << out << " (" << r.csi << " rf_msgs/Wifi on /csi, " << r.bearings
              << " rf_msgs/Bearing on /bearing" << (r.rc ? ", kept valid up to the fault" : "")
              << ")\n";
    return conversionExitStatus(r.rc, r.summary, "csi-export");
#else
    (void)in, (void)format, (void)options, (void)rxId, (void)showProgress;
    throw std::runtime_error(
        "--bag " + out +
        ": this build has no ROS 1 bag support (install librosbag-dev: "
        "scripts/install-deps.sh, then rebuild)");
#endif
}

/** --mcap: the same as --bag, as a ROS 2 recording (rosbag2's MCAP storage: rf_msgs/msg/Wifi
 *  on /csi and rf_msgs/msg/Bearing on /bearing, CDR). */
int exportMcap(
    const std::string& in, const std::string& format, const CsiDecodeOptions& options,
    const std::string& out, const std::string& rxId, mcap::Compression compression,
    bool showProgress)
{
    mcap::Writer writer(out, mcap::WriterOptions{compression});
    const auto& wifi = ros2::wifiType();
    const auto& bearing = ros2::bearingType();
    // Channels are added with their first message: a file without bearings has no /bearing.
    constexpr uint16_t kNoChannel = 0xFFFF;
    uint16_t csiChannel = kNoChannel, bearingChannel = kNoChannel;
    const auto stamp = [](mrpt::Clock::time_point t)
    { return ros2::Time::fromSeconds(mrpt::Clock::toDouble(t)).nanoseconds(); };
    const auto r = forEachExportedMessage(
        in, format, options, showProgress,
        [&](const CObservationWiFiCSI& o)
        {
            if (csiChannel == kNoChannel)
                csiChannel = writer.addRos2Channel("/csi", wifi.name, wifi.definition);
            writer.write(
                csiChannel, stamp(o.timestamp),
                ros2::serializeCdr(ros1::fromObservation(o, receiverId(o, rxId))));
        },
        [&](const CObservationWiFiBearing& b)
        {
            if (bearingChannel == kNoChannel)
                bearingChannel =
                    writer.addRos2Channel("/bearing", bearing.name, bearing.definition);
            writer.write(
                bearingChannel, stamp(b.timestamp), ros2::serializeCdr(ros1::fromBearing(b)));
        });
    // Closing writes the summary: what was converted before a fault stays readable. A write
    // error (disk full) throws here, naming the file.
    writer.close();
    std::cerr << r.summary.asString() << "\n"
              << "Output: " << out << " (" << r.csi << " rf_msgs/msg/Wifi on /csi, " << r.bearings
              << " rf_msgs/msg/Bearing on /bearing"
              << (writer.failed() ? ", incomplete: writing it failed"
                  : r.rc          ? ", kept valid up to the fault"
                                  : "")
              << ")\n";
    return conversionExitStatus(r.rc, r.summary, "csi-export");
}
}  // namespace

int main(int argc, char** argv)
{
    return cli::runMain(
        "csi-export",
        [&]
        {
            TCLAP::CmdLine cmd(
                "Exports the CSI frames of a capture in any supported format (Nexmon pcap of any "
                "chip, Intel 5300 .dat, ESP32 CSI_DATA lines, WiROS ROS 1 bags) or an mrpt_wifi "
                "rawlog as JSON "
                "Lines: one object per frame with timestamp, seq, mac, rssi, chanspec, channel, "
                "bw, nfft, chip, n_rx, n_tx, present[tx][rx], source, subcarriers (the indices k "
                "that carry a measurement), rssi_antennas, noise_floor / agc / csi_scale when "
                "the source reports them, and csi[tx][rx][bin] = [re, im] in subcarrier order "
                "(bin = k + nfft/2; the source's raw values, scaled = csi_scale * csi).",
                ' ', "0.1");
            TCLAP::UnlabeledValueArg<std::string> argIn(
                "input", "Input capture or rawlog", true, "", "IN", cmd);
            TCLAP::ValueArg<std::string> argJsonl(
                "", "jsonl", "Output JSON Lines file ('-' for stdout)", false, "", "OUT.jsonl",
                cmd);
            TCLAP::SwitchArg argStats(
                "", "stats",
                "Instead of exporting: frames per transmitter and channel, complete and incomplete",
                cmd);
            TCLAP::ValueArg<std::string> argBag(
                "", "bag",
                "Output ROS 1 bag as WiROS records it: rf_msgs/Wifi on /csi (and, from a rawlog, "
                "its CObservationWiFiBearing as rf_msgs/Bearing on /bearing: aoa = [AoA in the "
                "receive array's frame, rad])",
                false, "", "OUT.bag", cmd);
            TCLAP::ValueArg<std::string> argMcap(
                "", "mcap",
                "Output ROS 2 recording (MCAP, as rosbag2 writes it; opens in Foxglove): "
                "rf_msgs/msg/Wifi on /csi and, from a rawlog, rf_msgs/msg/Bearing on /bearing, "
                "CDR-encoded, the same fields as --bag",
                false, "", "OUT.mcap", cmd);
            TCLAP::ValueArg<std::string> argCompression(
                "", "compression", "With --mcap: chunk compression zstd|lz4|none", false, "zstd",
                "ALGO", cmd);
            TCLAP::ValueArg<std::string> argRxId(
                "", "rx-id",
                "With --bag or --mcap: rx_id of the messages (default: each frame's router "
                "address, else "
                "its sensor label)",
                false, "", "ID", cmd);
            TCLAP::ValueArg<std::string> argFormat(
                "f", "format",
                "Input format (or the Nexmon header variant): " + formatOptionChoices(), false,
                "auto", "FORMAT", cmd);
            TCLAP::ValueArg<std::string> argChannel(
                "", "channel",
                "Channel CH/BW for formats whose records carry none (Intel 5300 .dat)", false, "",
                "CH/BW", cmd);
            TCLAP::ValueArg<std::string> argBins(
                "", "overwritten-bins", "Firmware-overwritten bins of captures: keep|repair|mask",
                false, "repair", "POLICY", cmd);
            TCLAP::ValueArg<unsigned> argPort(
                "p", "port", "UDP port of the CSI datagrams in captures (0: any)", false, 5500,
                "PORT", cmd);
            TCLAP::SwitchArg argStrict("", "strict", kStrictOptionHelp, cmd);
            TCLAP::SwitchArg argQuiet("q", "quiet", "No progress display", cmd);
            if (const int rc = cli::parseCommandLine(cmd, argc, const_cast<const char**>(argv));
                rc >= 0)
                return rc;

            CsiDecodeOptions options;
            options.udpPort = uint16_t(argPort.getValue());
            const std::string format = applyFormatOption(argFormat.getValue(), options);
            options.strict = argStrict.getValue();
            if (argChannel.isSet()) options.chanspec = Chanspec::fromString(argChannel.getValue());
            options.assembler.overwrittenBins = overwrittenBinPolicyFromString(argBins.getValue());

            if (int(argJsonl.isSet()) + int(argStats.isSet()) + int(argBag.isSet()) +
                    int(argMcap.isSet()) !=
                1)
                throw std::invalid_argument(
                    "give exactly one of --jsonl OUT, --stats, --bag OUT and --mcap OUT");
            const auto compression = mcap::compressionFromString(argCompression.getValue());
            if (argMcap.isSet())
                return exportMcap(
                    argIn.getValue(), format, options, argMcap.getValue(), argRxId.getValue(),
                    compression, !argQuiet.getValue());
            if (argBag.isSet())
                return exportBag(
                    argIn.getValue(), format, options, argBag.getValue(), argRxId.getValue(),
                    !argQuiet.getValue());
            const bool toStdout = argStats.isSet() || argJsonl.getValue() == "-";
            std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(
                toStdout ? stdout : std::fopen(argJsonl.getValue().c_str(), "w"),
                toStdout ? [](std::FILE*) { return 0; } : &std::fclose);
            if (!file) throw std::runtime_error("cannot create '" + argJsonl.getValue() + "'");
            struct Count
            {
                uint64_t complete = 0, incomplete = 0;
            };
            std::map<std::pair<std::string, std::string>, Count> counts;  // (MAC, channel)
            const auto onFrame = [&](CObservationWiFiCSI::Ptr&& obs)
            {
                if (!argStats.isSet()) return writeJsonLine(file.get(), *obs);
                auto& c = counts[{obs->transmitter.asString(), obs->chanspec.asString()}];
                ++(obs->isComplete() ? c.complete : c.incomplete);
            };

            cli::Progress progress("csi-export", !argQuiet.getValue() && !toStdout);
            CsiDecodeSummary summary;
            int rc = 0;
            try
            {
                decodeCsiFile(
                    argIn.getValue(), format, options, onFrame,
                    [&](double f) { progress.update(f); }, &summary);
                progress.done(std::to_string(summary.frames) + " frames");
            }
            catch (const std::exception& e)
            {
                std::cerr << "\ncsi-export: error: " << e.what() << "\n";
                rc = 1;
            }
            if (std::fflush(file.get()) != 0)
                throw std::runtime_error("writing '" + argJsonl.getValue() + "' failed");
            if (argStats.isSet())
            {
                std::printf(
                    "%-19s %-8s %10s %10s\n", "TRANSMITTER", "CHANNEL", "COMPLETE", "INCOMPLETE");
                Count total;
                for (const auto& [key, c] : counts)
                {
                    std::printf(
                        "%-19s %-8s %10" PRIu64 " %10" PRIu64 "\n", key.first.c_str(),
                        key.second.c_str(), c.complete, c.incomplete);
                    total.complete += c.complete;
                    total.incomplete += c.incomplete;
                }
                std::printf(
                    "%-28s %10" PRIu64 " %10" PRIu64 "\n", "total", total.complete,
                    total.incomplete);
            }
            std::cerr << summary.asString() << "\n";
            if (rc == 0 && summary.frames == 0)
            {
                std::cerr << "csi-export: no CSI frame in '" << argIn.getValue() << "'\n";
                return cli::kExitNoMatchingFrames;
            }
            return conversionExitStatus(rc, summary, "csi-export");
        });
}
