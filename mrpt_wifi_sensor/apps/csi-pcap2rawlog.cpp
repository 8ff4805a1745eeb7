/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * csi-pcap2rawlog: converts a tcpdump capture of Nexmon CSI datagrams into an MRPT rawlog of
 * mrpt_wifi::CObservationWiFiCSI, one observation per overheard frame. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/sensor/CsiFileReader.h>

#include <iostream>

using namespace mrpt_wifi;

int main(int argc, char** argv)
{
    return cli::runMain(
        "csi-pcap2rawlog",
        [&]
        {
            TCLAP::CmdLine cmd(
                "Converts a tcpdump capture (pcap/pcapng) of Nexmon CSI datagrams from an "
                "RT-AC86U into an MRPT rawlog of mrpt_wifi::CObservationWiFiCSI observations.",
                ' ', "0.1");
            TCLAP::UnlabeledValueArg<std::string> argIn(
                "input", "Input capture (.pcap, .pcapng)", true, "", "IN.pcap", cmd);
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
                "f", "format", "Datagram header: auto|nexmon|nexmon-legacy|ubilocate", false,
                "auto", "FORMAT", cmd);
            TCLAP::ValueArg<std::string> argBins(
                "", "overwritten-bins", "Firmware-overwritten bins: keep|repair|mask", false,
                "repair", "POLICY", cmd);
            TCLAP::ValueArg<unsigned> argPort(
                "p", "port", "UDP destination port of the CSI datagrams (0: any)", false, 5500,
                "PORT", cmd);
            TCLAP::ValueArg<double> argTimeout(
                "", "frame-timeout", "Seconds after which an incomplete frame is written as it is",
                false, 0.1, "S", cmd);
            TCLAP::SwitchArg argQuiet("q", "quiet", "No progress display", cmd);

            cli::JoinedArgv args(argc, argv, "--sensor-pose", 6);
            if (const int rc = cli::parseCommandLine(cmd, args.argc(), args.argv()); rc >= 0)
                return rc;

            CsiFileReadOptions options;
            options.udpPort = uint16_t(argPort.getValue());
            options.assembler.format = nexmon::formatHintFromString(argFormat.getValue());
            options.assembler.overwrittenBins = overwrittenBinPolicyFromString(argBins.getValue());
            options.assembler.frameTimeout_s = argTimeout.getValue();
            options.assembler.sensorLabel = argLabel.getValue();
            options.assembler.sensorPose = cli::poseFromText(argPose.getValue(), "--sensor-pose");
            if (detectCsiFileKind(argIn.getValue()) != CsiFileKind::Pcap)
                throw std::runtime_error("'" + argIn.getValue() + "' is not a pcap/pcapng capture");

            mrpt::io::CFileGZOutputStream out;
            if (!out.open(argOut.getValue()))
                throw std::runtime_error("cannot create rawlog '" + argOut.getValue() + "'");
            auto archive = mrpt::serialization::archiveFrom(out);

            cli::Progress progress("csi-pcap2rawlog", !argQuiet.getValue());
            CsiFileReadSummary summary;
            uint64_t written = 0;
            int rc = 0;
            try
            {
                readCsiFrames(
                    argIn.getValue(), options,
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
                std::cerr << "\ncsi-pcap2rawlog: error: " << e.what() << "\n";
                rc = 1;
            }
            out.close();
            std::cout << "Input : " << argIn.getValue() << "\n"
                      << summary.asString() << "\n"
                      << "Output: " << argOut.getValue() << " (" << written
                      << " CObservationWiFiCSI" << (rc ? ", kept valid up to the fault" : "")
                      << ")\n";
            return rc;
        });
}
