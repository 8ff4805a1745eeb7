/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * wifi-bearings-synth: "bearings from elsewhere" for development and tests. Turns the true
 * angles of a simulation (frames.csv of `wifi-sim --truth-dir`) into the documented bearings CSV
 * with a stated error model (Gaussian noise, outliers, multipath peaks, mirror ambiguity of
 * linear arrays). It is not an estimator: use csi-bearings on the CSI for that. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/core/bits_math.h>
#include <mrpt_wifi/localization/SyntheticBearings.h>
#include <mrpt_wifi/obs/CommandLine.h>

#include <iostream>

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;

int main(int argc, char** argv)
{
    return cli::runMain(
        "wifi-bearings-synth",
        [&]
        {
            TCLAP::CmdLine cmd(
                "Makes a bearings CSV (the format wifi-pf-localization, wifi-graphslam and "
                "wifi-iot-map read) from a simulation's true angles plus a stated error model.",
                ' ', "0.1");
            TCLAP::UnlabeledValueArg<std::string> argFrames(
                "frames", "frames.csv of wifi-sim --truth-dir", true, "", "frames.csv", cmd);
            TCLAP::UnlabeledValueArg<std::string> argTx(
                "transmitters", "transmitters.yaml of the same run", true, "", "TX.yaml", cmd);
            TCLAP::UnlabeledValueArg<std::string> argOut(
                "output", "Bearings CSV to write", true, "", "OUT.csv", cmd);
            TCLAP::ValueArg<std::string> argRx(
                "", "rx-array", "Robot's antenna array file (linear: mirror candidates)", false, "",
                "ARRAY.yaml", cmd);
            TCLAP::ValueArg<double> argAoaStd(
                "", "aoa-std", "AoA error sigma [deg]", false, 3.0, "DEG", cmd);
            TCLAP::ValueArg<double> argAodStd(
                "", "aod-std", "AoD error sigma [deg]", false, 4.0, "DEG", cmd);
            TCLAP::ValueArg<double> argOut_(
                "", "outliers", "Fraction of angles replaced by uniform ones", false, 0.03, "F",
                cmd);
            TCLAP::ValueArg<double> argRate(
                "", "rate", "Bearings per second and transmitter (0: every frame)", false, 10, "HZ",
                cmd);
            TCLAP::SwitchArg argNoAod("", "no-aod", "AoA only", cmd);
            TCLAP::SwitchArg argLos(
                "", "los-only", "Never report a stronger multipath peak instead of the LoS", cmd);
            TCLAP::ValueArg<unsigned> argSeed("s", "seed", "Random seed", false, 1, "N", cmd);
            if (const int rc = cli::parseCommandLine(cmd, argc, (const char**)argv); rc >= 0)
                return rc;

            const auto txs = TransmitterMap::fromYamlFile(argTx.getValue());
            SyntheticBearingOptions o;
            o.aoaStd_rad = mrpt::DEG2RAD(argAoaStd.getValue());
            o.aodStd_rad = mrpt::DEG2RAD(argAodStd.getValue());
            o.outlierFraction = argOut_.getValue();
            o.rate_Hz = argRate.getValue();
            o.aod = !argNoAod.getValue();
            o.strongestPathErrors = !argLos.getValue();
            o.seed = argSeed.getValue();
            o.rxArray =
                argRx.isSet() ? loadArrayFile(argRx.getValue()) : ArrayGeometry::fromElements({});
            SyntheticBearingStats st;
            const auto recs = synthesizeBearings(argFrames.getValue(), txs, o, &st);
            writeBearingCsv(argOut.getValue(), recs);
            std::cout << "wifi-bearings-synth: " << st.frames << " frames, " << st.kept
                      << " bearings written to " << argOut.getValue() << " (" << st.outliers
                      << " outliers, " << st.strongestPath << " multipath peaks, "
                      << st.unknownTransmitter << " frames of unknown transmitters skipped)\n";
            return 0;
        });
}
