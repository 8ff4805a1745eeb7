/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * csi-export: writes the CSI frames of a capture or rawlog as JSON Lines, one object per
 * frame, for Python/MATLAB users. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/sensor/CsiFileReader.h>

#include <cinttypes>
#include <cstdio>
#include <iostream>
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
    std::fputs("],\"csi\":[", f);
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
}  // namespace

int main(int argc, char** argv)
{
    return cli::runMain(
        "csi-export",
        [&]
        {
            TCLAP::CmdLine cmd(
                "Exports the CSI frames of a Nexmon capture (.pcap/.pcapng) or an mrpt_wifi "
                "rawlog as JSON Lines: one object per frame with timestamp, seq, mac, rssi, "
                "chanspec, channel, bw, nfft, chip, n_rx, n_tx, present[tx][rx] and "
                "csi[tx][rx][bin] = [re, im] in subcarrier order (bin = k + nfft/2).",
                ' ', "0.1");
            TCLAP::UnlabeledValueArg<std::string> argIn(
                "input", "Input capture or rawlog", true, "", "IN", cmd);
            TCLAP::ValueArg<std::string> argJsonl(
                "", "jsonl", "Output JSON Lines file ('-' for stdout)", true, "", "OUT.jsonl", cmd);
            TCLAP::ValueArg<std::string> argFormat(
                "f", "format", "Datagram header of captures: auto|nexmon|nexmon-legacy|ubilocate",
                false, "auto", "FORMAT", cmd);
            TCLAP::ValueArg<std::string> argBins(
                "", "overwritten-bins", "Firmware-overwritten bins of captures: keep|repair|mask",
                false, "repair", "POLICY", cmd);
            TCLAP::ValueArg<unsigned> argPort(
                "p", "port", "UDP port of the CSI datagrams in captures (0: any)", false, 5500,
                "PORT", cmd);
            TCLAP::SwitchArg argQuiet("q", "quiet", "No progress display", cmd);
            if (const int rc = cli::parseCommandLine(cmd, argc, const_cast<const char**>(argv));
                rc >= 0)
                return rc;

            CsiFileReadOptions options;
            options.udpPort = uint16_t(argPort.getValue());
            options.assembler.format = nexmon::formatHintFromString(argFormat.getValue());
            options.assembler.overwrittenBins = overwrittenBinPolicyFromString(argBins.getValue());

            const bool toStdout = argJsonl.getValue() == "-";
            std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(
                toStdout ? stdout : std::fopen(argJsonl.getValue().c_str(), "w"),
                toStdout ? [](std::FILE*) { return 0; } : &std::fclose);
            if (!file) throw std::runtime_error("cannot create '" + argJsonl.getValue() + "'");

            cli::Progress progress("csi-export", !argQuiet.getValue() && !toStdout);
            CsiFileReadSummary summary;
            int rc = 0;
            try
            {
                readCsiFrames(
                    argIn.getValue(), options,
                    [&](CObservationWiFiCSI::Ptr&& obs) { writeJsonLine(file.get(), *obs); },
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
            std::cerr << summary.asString() << "\n";
            return rc;
        });
}
