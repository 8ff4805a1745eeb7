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

#include <cinttypes>
#include <cmath>
#include <cstdio>
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
/** --bag: CSI (and a rawlog's bearings) as WiROS's messages. */
int exportBag(
    const std::string& in, const std::string& format, const CsiDecodeOptions& options,
    const std::string& out, const std::string& rxId, bool showProgress)
{
#if MRPT_WIFI_HAVE_ROSBAG
    ros1::BagWriter bag(out);
    uint64_t csi = 0, bearings = 0;
    const auto writeCsi = [&](const CObservationWiFiCSI& o)
    {
        const std::string id = !rxId.empty()              ? rxId
                               : !o.routerAddress.empty() ? o.routerAddress
                                                          : o.sensorLabel;
        const auto m = ros1::fromObservation(o, id);
        bag.write("/csi", mrpt::Clock::toDouble(o.timestamp), ros1::wifiType(), ros1::serialize(m));
        ++csi;
    };
    cli::Progress progress("csi-export", showProgress);
    const auto onProgress = [&](double f) {
        progress.update(f, std::to_string(csi) + " CSI, " + std::to_string(bearings) + " bearings");
    };
    CsiDecodeSummary summary;
    int rc = 0;
    try
    {
        const auto decoder = format == "auto" ? CsiDecoderRegistry::instance().detect(in)
                                              : CsiDecoderRegistry::instance().find(format);
        if (decoder && decoder->name() == "rawlog")
        {
            // A rawlog may hold bearings too (csi-bearings' output): both go to the bag.
            summary.format = "rawlog";
            summary.records = forEachRawlogObservation(
                in,
                [&](const mrpt::obs::CObservation::Ptr& o)
                {
                    if (auto c = std::dynamic_pointer_cast<CObservationWiFiCSI>(o))
                        writeCsi(*c), ++summary.frames;
                    else if (auto b = std::dynamic_pointer_cast<CObservationWiFiBearing>(o))
                    {
                        bag.write(
                            "/bearing", mrpt::Clock::toDouble(b->timestamp), ros1::bearingType(),
                            ros1::serialize(ros1::fromBearing(*b)));
                        ++bearings;
                    }
                },
                onProgress);
        }
        else
            decodeCsiFile(
                in, format, options, [&](CObservationWiFiCSI::Ptr&& o) { writeCsi(*o); },
                onProgress, &summary);
        progress.done(std::to_string(csi) + " CSI, " + std::to_string(bearings) + " bearings");
    }
    catch (const std::exception& e)
    {
        std::cerr << "\ncsi-export: error: " << e.what() << "\n";
        rc = 1;
    }
    bag.close();
    std::cerr << summary.asString() << "\n"
              << "Output: " << out << " (" << csi << " rf_msgs/Wifi on /csi, " << bearings
              << " rf_msgs/Bearing on /bearing" << (rc ? ", kept valid up to the fault" : "")
              << ")\n";
    return conversionExitStatus(rc, summary, "csi-export");
#else
    (void)in, (void)format, (void)options, (void)rxId, (void)showProgress;
    throw std::runtime_error(
        "--bag " + out +
        ": this build has no ROS 1 bag support (install librosbag-dev: "
        "scripts/install-deps.sh, then rebuild)");
#endif
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
            TCLAP::ValueArg<std::string> argRxId(
                "", "rx-id",
                "With --bag: rx_id of the messages (default: each frame's router address, else "
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

            if (int(argJsonl.isSet()) + int(argStats.isSet()) + int(argBag.isSet()) != 1)
                throw std::invalid_argument(
                    "give exactly one of --jsonl OUT, --stats and --bag OUT");
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
