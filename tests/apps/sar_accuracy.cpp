/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * sar-accuracy: synthetic-aperture bearings (wifi-sar's chain) over random rooms of the
 * simulator (or the registered estimator `sar` in a BearingProcessor, --bearing-chain),
 * development seeds 1.. or evaluation seeds 1000.. (SarAccuracy.h says what a room
 * is). Per room the three peers' errors, then the summary the README's table quotes. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt_wifi/obs/CommandLine.h>

#include <algorithm>
#include <cstdio>

#include "SarAccuracy.h"

using namespace mrpt_wifi;

int main(int argc, char** argv)
{
    return cli::runMain(
        "sar-accuracy",
        [&]
        {
            TCLAP::CmdLine cmd(
                "Synthetic-aperture bearings over random simulated rooms (issue 18)", ' ', "0.1");
            TCLAP::ValueArg<unsigned> argRooms("", "rooms", "Number of rooms", false, 20, "N", cmd);
            TCLAP::SwitchArg argEval(
                "", "eval", "Evaluation seeds (1000..) instead of development seeds (1..)", cmd);
            TCLAP::ValueArg<double> argPosErr(
                "", "position-error",
                "RMS of a smooth error added to the positions the estimator sees [m] (a "
                "tracking camera's: about 0.02)",
                false, 0.0, "M", cmd);
            TCLAP::ValueArg<double> argPosStd(
                "", "position-std", "The estimator's SarOptions::positionStd_m [m]", false, 0.0,
                "M", cmd);
            TCLAP::SwitchArg argChain(
                "", "bearing-chain",
                "Through the registered estimator 'sar' in a BearingProcessor (as csi-bearings "
                "runs it on a rawlog with both recordings and odometry; the last bearing per peer, "
                "from the pose of its frame) instead of wifi-sar's chain",
                cmd);
            if (const int rc = cli::parseCommandLine(cmd, argc, const_cast<const char**>(argv));
                rc >= 0)
                return rc;
            const uint32_t first = argEval.getValue() ? sim::kFirstEvaluationSeed : 1;
            std::vector<double> errors;
            size_t covered = 0, failed = 0, roomsMeeting = 0;
            cli::Progress progress("rooms");
            std::printf("room  size [m]      |error| per peer [deg] (sigma)\n");
            for (unsigned i = 0; i < argRooms.getValue(); ++i)
            {
                const auto room = sartest::runRoom(
                    first + i, std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays",
                    argPosErr.getValue(), argPosStd.getValue(), argChain.getValue());
                std::printf("%4u  %4.1f x %4.1f ", room.seed, room.width, room.height);
                double worst = 0;
                for (const auto& p : room.peers)
                {
                    if (!p.estimated)
                    {
                        ++failed, worst = 1e9;
                        std::printf("   none       ");
                        continue;
                    }
                    errors.push_back(std::abs(p.error_deg));
                    covered += std::abs(p.error_deg) <= 3 * p.std_deg;
                    worst = std::max(worst, std::abs(p.error_deg));
                    std::printf(" %6.2f (%5.2f)", std::abs(p.error_deg), p.std_deg);
                }
                std::printf("\n");
                roomsMeeting += worst <= 5.0;
                progress.update(double(i + 1) / argRooms.getValue());
            }
            progress.done();
            std::sort(errors.begin(), errors.end());
            double mean = 0;
            for (double e : errors) mean += e;
            mean /= double(std::max<size_t>(errors.size(), 1));
            const auto at = [&](double q)
            { return errors.empty() ? 0.0 : errors[size_t(q * double(errors.size() - 1))]; };
            std::printf(
                "summary (%s seeds, position error %.3f m): %zu bearings, %zu peers without one; "
                "|error| mean %.2f, median %.2f, p90 %.2f, max %.2f deg; %.1f %% > 30 deg; "
                "%.1f %% within 3 sigma; %zu of %u rooms with every peer within 5 deg\n",
                argEval.getValue() ? "evaluation" : "development", argPosErr.getValue(),
                errors.size(), failed, mean, at(0.5), at(0.9), errors.empty() ? 0.0 : errors.back(),
                100.0 *
                    double(std::count_if(
                        errors.begin(), errors.end(), [](double e) { return e > 30; })) /
                    double(std::max<size_t>(errors.size(), 1)),
                100.0 * double(covered) / double(std::max<size_t>(errors.size(), 1)), roomsMeeting,
                argRooms.getValue());
            return 0;
        });
}
