/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * csi-import (also built as csi-pcap2rawlog, its first name): converts a CSI capture of any
 * supported source (Nexmon pcap of any chip, Intel 5300 .dat, ESP32 CSI_DATA lines, WiROS's
 * ROS 1 and ROS 2 bags) into an MRPT rawlog of mrpt_wifi::CObservationWiFiCSI, one observation
 * per overheard frame. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <mrpt_wifi/sensor/CsiFileReader.h>

#include <filesystem>
#include <iostream>

using namespace mrpt_wifi;

int main(int argc, char** argv)
{
    const std::string program = std::filesystem::path(argv[0]).filename().string();
    return cli::runMain(
        program,
        [&]
        {
            std::string formats;
            for (const auto& d : CsiDecoderRegistry::instance().all())
                if (d->name() != "rawlog") formats += "\n  " + d->name() + ": " + d->description();
            TCLAP::CmdLine cmd(
                "Converts a CSI capture into an MRPT rawlog of mrpt_wifi::CObservationWiFiCSI "
                "observations. The format is detected from the content (not the file name); "
                "--format forces one. csi-pcap2rawlog is the old name of csi-import, kept as an "
                "alias. Formats:" +
                    formats,
                ' ', "0.1");
            TCLAP::UnlabeledValueArg<std::string> argIn(
                "input",
                "Input capture (.pcap, .pcapng, .dat, .csv/.txt of CSI_DATA lines, ROS 1 .bag, "
                "ROS 2 .mcap / .db3 or a ROS 2 bag directory)",
                true, "", "IN", cmd);
            TCLAP::UnlabeledValueArg<std::string> argOut(
                "output", "Output rawlog", true, "", "OUT.rawlog", cmd);
            TCLAP::ValueArg<std::string> argLabel(
                "l", "sensor-label", "Sensor label of the observations", false, "WIFI_CSI", "LABEL",
                cmd);
            TCLAP::ValueArg<std::string> argPose(
                "", "sensor-pose",
                "Pose of the receive array on the robot: x y z yaw pitch roll (m, deg)", false,
                "0 0 0 0 0 0", "x y z yaw pitch roll", cmd);
            TCLAP::ValueArg<std::string> argFormat(
                "f", "format",
                "Input format (or the Nexmon header variant): " + formatOptionChoices(), false,
                "auto", "FORMAT", cmd);
            TCLAP::ValueArg<std::string> argChannel(
                "", "channel",
                "Channel CH/BW for formats whose records carry none (Intel 5300 .dat)", false, "",
                "CH/BW", cmd);
            TCLAP::ValueArg<std::string> argBins(
                "", "overwritten-bins", "Firmware-overwritten bins: keep|repair|mask", false,
                "repair", "POLICY", cmd);
            TCLAP::ValueArg<unsigned> argPort(
                "p", "port", "UDP destination port of the CSI datagrams (0: any)", false, 5500,
                "PORT", cmd);
            TCLAP::ValueArg<double> argTimeout(
                "", "frame-timeout", "Seconds after which an incomplete frame is written as it is",
                false, 0.1, "S", cmd);
            TCLAP::SwitchArg argEsp32Lltf(
                "", "esp32-lltf",
                "ESP32 lines: keep the L-LTF (52 subcarriers) even when the line has an HT-LTF "
                "(by default the HT-LTF, and with STBC both space-time streams)",
                cmd);
            TCLAP::SwitchArg argStrict("", "strict", kStrictOptionHelp, cmd);
            TCLAP::SwitchArg argQuiet("q", "quiet", "No progress display", cmd);

            cli::JoinedArgv args(argc, argv, "--sensor-pose", 6);
            if (const int rc = cli::parseCommandLine(cmd, args.argc(), args.argv()); rc >= 0)
                return rc;

            CsiDecodeOptions options;
            options.udpPort = uint16_t(argPort.getValue());
            const std::string format = applyFormatOption(argFormat.getValue(), options);
            options.strict = argStrict.getValue();
            if (argChannel.isSet()) options.chanspec = Chanspec::fromString(argChannel.getValue());
            options.esp32LegacyLtf = argEsp32Lltf.getValue();
            options.assembler.overwrittenBins = overwrittenBinPolicyFromString(argBins.getValue());
            options.assembler.frameTimeout_s = argTimeout.getValue();
            options.assembler.sensorLabel = argLabel.getValue();
            options.assembler.sensorPose = cli::poseFromText(argPose.getValue(), "--sensor-pose");
            const auto decoder = format == "auto"
                                     ? CsiDecoderRegistry::instance().detect(argIn.getValue())
                                     : CsiDecoderRegistry::instance().find(format);
            if (decoder->name() == "rawlog")
                throw std::runtime_error(
                    "'" + argIn.getValue() + "' is already a rawlog, not a capture");

            mrpt::io::CFileGZOutputStream out;
            if (!out.open(argOut.getValue()))
                throw std::runtime_error("cannot create rawlog '" + argOut.getValue() + "'");
            auto archive = mrpt::serialization::archiveFrom(out);

            cli::Progress progress(program, !argQuiet.getValue());
            CsiDecodeSummary summary;
            uint64_t written = 0;
            int rc = 0;
            try
            {
                decodeCsiFile(
                    argIn.getValue(), decoder->name(), options,
                    [&](CObservationWiFiCSI::Ptr&& obs)
                    {
                        archive << *obs;
                        ++written;
                    },
                    [&](double f) { progress.update(f, std::to_string(written) + " frames"); },
                    &summary);
                progress.done(std::to_string(written) + " frames");
            }
            catch (const std::exception& e)
            {
                // Everything converted before the fault is already in the rawlog, which the
                // stream closes cleanly below.
                std::cerr << "\n" << program << ": error: " << e.what() << "\n";
                rc = 1;
            }
            out.close();
            std::cout << "Input : " << argIn.getValue() << "\n"
                      << summary.asString() << "\n"
                      << "Output: " << argOut.getValue() << " (" << written
                      << " CObservationWiFiCSI" << (rc ? ", kept valid up to the fault" : "")
                      << ")\n";
            if (rc == 0 && written == 0)
            {
                // Nothing to work with is a failure a script must see.
                std::cerr << program << ": no CSI frame in '" << argIn.getValue()
                          << "' (the summary above says what was read and why it was skipped)\n";
                return cli::kExitNoMatchingFrames;
            }
            return conversionExitStatus(rc, summary, program);
        });
}
