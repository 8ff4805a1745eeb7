/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/random/RandomGenerators.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sim/CsiSynthesizer.h>
#include <mrpt_wifi/sim/PacketExchange.h>

#include <cmath>
#include <complex>

namespace mrpt_wifi::sim
{
namespace
{
using cd = std::complex<double>;

/** One reception: the reciprocal channel with this side's impairments, quantised to int8. */
CObservationWiFiCSI::Ptr reception(
    const std::vector<cd>& channel, const std::vector<int>& ks, const ExchangeOptions& o,
    double oscillatorPhase, double noiseStd, double quantScale, mrpt::random::CRandomGenerator& rng)
{
    auto f = CObservationWiFiCSI::Create();
    f->source = "iwl5300-wsr";
    f->chanspec = o.chanspec;
    f->resize(1, 1, o.chanspec.nfft());
    f->subcarrierIndices.assign(ks.begin(), ks.end());
    const double delay = rng.drawUniform(0.0, o.maxDetectionDelay_s);
    const double df = 312.5e3;
    for (size_t i = 0; i < ks.size(); ++i)
    {
        cd h = channel[i] * std::polar(1.0, oscillatorPhase - 2 * M_PI * ks[i] * df * delay);
        h += cd(rng.drawGaussian1D(0, noiseStd), rng.drawGaussian1D(0, noiseStd));
        h *= quantScale;
        const auto q = [](double v) { return float(std::clamp(std::round(v), -128.0, 127.0)); };
        f->at(0, 0, subcarrierToBin(ks[i], o.chanspec.nfft())) = {q(h.real()), q(h.imag())};
    }
    f->setPresent(0, 0);
    return f;
}
}  // namespace

ExchangeRecording simulateExchanges(
    const ChannelModel& channel, const std::function<mrpt::math::TPoint2D(double)>& moverAt,
    double t0, double t1, const MacAddress& moverMac, const std::vector<ExchangePeer>& peers,
    const ExchangeOptions& o, uint32_t seed)
{
    mrpt::random::CRandomGenerator rng(seed);
    const auto& ks = htGroupedSubcarriers(o.chanspec.bandwidthMHz);
    const double wavelength = kSpeedOfLight / o.chanspec.centerFrequencyHz();
    ExchangeRecording out;
    out.heardByPeer.resize(peers.size());
    std::vector<PropagationPath> paths;
    // Both radios have one antenna: the synthesizer's single-element arrays (no array phase).
    const auto single = AntennaArray::singleElement();
    const ArrayPlacement antenna{&single, 0.0, 1};
    CsiSynthesizer synthesizer;
    std::vector<std::complex<float>> bins;
    std::vector<cd> h(ks.size());
    for (size_t m = 0; m < peers.size(); ++m)
    {
        const auto images = channel.imagesOf(peers[m].position);
        uint32_t counter = 0;
        // Peers take turns: each starts at its own slot within the period.
        for (double t = t0 + double(m) / (o.rate_Hz * double(peers.size())); t < t1;
             t += 1.0 / o.rate_Hz)
        {
            ++counter;
            channel.computePaths(images, moverAt(t), wavelength, paths);
            synthesizer.synthesize(paths, antenna, antenna, o.chanspec, bins);
            for (size_t i = 0; i < ks.size(); ++i)
                h[i] = cd(bins[subcarrierToBin(ks[i], o.chanspec.nfft())]);
            double power = 0;
            for (const auto& v : h) power += std::norm(v);
            power /= double(h.size());
            if (!(power > 0)) continue;
            const double noiseStd = std::sqrt(power / std::pow(10.0, o.snr_dB / 10) / 2);
            // int8 values of a few tens, as the 5300 reports them.
            const double quantScale = 30.0 / std::sqrt(power);
            const double theta = rng.drawUniform(-M_PI, M_PI);
            // The peer's packet heard by the robot, then the robot's reply heard by the peer.
            if (rng.drawUniform(0, 1) >= o.lossProbability)
            {
                auto f = reception(h, ks, o, theta, noiseStd, quantScale, rng);
                f->transmitter = peers[m].mac;
                f->firmwareCounter = uint16_t(counter & 0xFFFF);
                f->timestamp = mrpt::Clock::fromDouble(t);
                out.heardByMover.push_back(f);
            }
            if (rng.drawUniform(0, 1) >= o.lossProbability)
            {
                auto f = reception(
                    h, ks, o, -theta + rng.drawGaussian1D(0, o.turnaroundPhaseStd_rad), noiseStd,
                    quantScale, rng);
                f->transmitter = moverMac;
                f->firmwareCounter = uint16_t(counter & 0xFFFF);
                f->timestamp = mrpt::Clock::fromDouble(t + 0.002 + o.peerClockOffset_s);
                out.heardByPeer[m].push_back(f);
            }
        }
    }
    std::stable_sort(
        out.heardByMover.begin(), out.heardByMover.end(),
        [](const auto& a, const auto& b) { return a->timestamp < b->timestamp; });
    return out;
}

}  // namespace mrpt_wifi::sim
