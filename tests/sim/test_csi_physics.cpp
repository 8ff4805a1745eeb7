/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * Wideband CSI synthesis against closed forms: per-subcarrier steering phases (AoA and AoD),
 * delay slope across subcarriers, and the full multipath sum evaluated directly. */
#include <gtest/gtest.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sim/CsiSynthesizer.h>

#include <cmath>

using namespace mrpt_wifi;
using namespace mrpt_wifi::sim;
using mrpt::math::wrapToPi;

namespace
{
AntennaArray makeArray(std::vector<mrpt::math::TPoint2D> elements)
{
    AntennaArray a;
    a.name = "test";
    a.elements = std::move(elements);
    return a;
}

const AntennaArray kRtAc86u = makeArray({{0, 0}, {0, 0.052}, {0, 0.026}, {0, 0.078}});
const AntennaArray kSquare =
    makeArray({{0.013, 0.013}, {0.013, -0.013}, {-0.013, -0.013}, {-0.013, 0.013}});
const AntennaArray kSingle = AntennaArray::singleElement();

PropagationPath planeWave(
    double arrival_rad, double departure_rad, double length_m, double amp = 1e-3)
{
    PropagationPath p;
    p.arrival_rad = arrival_rad;
    p.departure_rad = departure_rad;
    p.length_m = length_m;
    p.delay_s = length_m / kSpeedOfLight;
    p.gain = std::polar(amp, 0.3);
    return p;
}

std::complex<double> at(
    const std::vector<std::complex<float>>& csi, unsigned nRx, unsigned nfft, unsigned m,
    unsigned i, int k)
{
    const auto v = csi[(size_t(m) * nRx + i) * nfft + subcarrierToBin(k, nfft)];
    return {v.real(), v.imag()};
}
}  // namespace

// LoS only: the phase of antenna i relative to antenna 0 is 2π/λ_k · (a_i − a_0)·u(θ) at every
// subcarrier, with θ the direction of the transmitter in the sensor frame and λ_k each
// subcarrier's own wavelength.
TEST(CsiPhysics, AoaPhaseDifferencePerSubcarrier)
{
    CsiSynthesizer synth;
    const Chanspec cs = Chanspec::make(155, 80);
    for (const AntennaArray* array : {&kRtAc86u, &kSquare})
        for (double thetaDeg : {0.0, 30.0, -70.0, 150.0, 95.0})
            for (double sensorYawDeg : {0.0, 40.0})
            {
                const double yaw = sensorYawDeg * M_PI / 180;
                const double theta = thetaDeg * M_PI / 180;  // in the sensor frame
                std::vector<std::complex<float>> csi;
                synth.synthesize(
                    {planeWave(theta + yaw, 0.0, 6.3)}, {array, yaw, 4}, {&kSingle, 0.0, 1}, cs,
                    csi);
                double worst = 0;
                for (int k : dataSubcarriers(80))
                {
                    const double lambda = kSpeedOfLight / subcarrierFrequencyHz(cs, k);
                    const auto h0 = at(csi, 4, 256, 0, 0, k);
                    for (unsigned i = 1; i < 4; ++i)
                    {
                        const auto& a = array->elements[i];
                        const auto& a0 = array->elements[0];
                        const double expected =
                            2 * M_PI / lambda *
                            ((a.x - a0.x) * std::cos(theta) + (a.y - a0.y) * std::sin(theta));
                        const double measured = std::arg(at(csi, 4, 256, 0, i, k) / h0);
                        worst = std::max(worst, std::abs(wrapToPi(measured - expected)));
                    }
                }
                EXPECT_LT(worst, 2e-4)
                    << array->name << " θ=" << thetaDeg << "° yaw=" << sensorYawDeg;
            }
}

// The same at the band edge is measurably different from a narrowband model (one wavelength for
// all subcarriers): the test above would catch a narrowband shortcut.
TEST(CsiPhysics, SteeringIsNotNarrowband)
{
    CsiSynthesizer synth;
    const Chanspec cs = Chanspec::make(155, 80);
    const double theta = 10 * M_PI / 180;
    std::vector<std::complex<float>> csi;
    synth.synthesize(
        {planeWave(theta, 0.0, 5.0)}, {&kRtAc86u, 0.0, 4}, {&kSingle, 0.0, 1}, cs, csi);
    const int k = 122;
    const double lambdaCenter = kSpeedOfLight / cs.centerFrequencyHz();
    const double narrowband = 2 * M_PI / lambdaCenter * 0.078 * std::sin(theta);
    const double measured = std::arg(at(csi, 4, 256, 0, 3, k) / at(csi, 4, 256, 0, 0, k));
    EXPECT_GT(std::abs(wrapToPi(measured - narrowband)), 1e-3);
}

// AoD: with one receive antenna and a transmit array, stream m's phase relative to stream 0 is
// 2π/λ_k · (b_m − b_0)·u(φ), φ the departure direction in the transmitter frame.
TEST(CsiPhysics, AodPhaseDifferencePerSubcarrier)
{
    CsiSynthesizer synth;
    const Chanspec cs = Chanspec::make(36, 40);
    const AntennaArray ap = makeArray({{0, -0.039}, {0, -0.013}, {0, 0.013}, {0, 0.039}});
    const double txYaw = 120 * M_PI / 180;
    for (double phiDeg : {-60.0, 0.0, 25.0, 80.0})
    {
        const double phi = phiDeg * M_PI / 180;
        std::vector<std::complex<float>> csi;
        synth.synthesize(
            {planeWave(2.0, phi + txYaw, 4.0)}, {&kSingle, 0.5, 1}, {&ap, txYaw, 4}, cs, csi);
        double worst = 0;
        for (int k : dataSubcarriers(40))
        {
            const double lambda = kSpeedOfLight / subcarrierFrequencyHz(cs, k);
            const auto h0 = at(csi, 1, 128, 0, 0, k);
            for (unsigned m = 1; m < 4; ++m)
            {
                const double expected =
                    2 * M_PI / lambda * (ap.elements[m].y - ap.elements[0].y) * std::sin(phi);
                worst = std::max(
                    worst, std::abs(wrapToPi(std::arg(at(csi, 1, 128, m, 0, k) / h0) - expected)));
            }
        }
        EXPECT_LT(worst, 2e-4) << "φ=" << phiDeg;
    }
}

// The phase of one path falls linearly across subcarriers with slope −2π·Δf·L/c: fitting the
// unwrapped phase gives back the path length.
TEST(CsiPhysics, PhaseSlopeAcrossSubcarriersIsPathLengthOverC)
{
    CsiSynthesizer synth;
    for (unsigned bw : {20u, 40u, 80u})
        for (double length : {1.7, 12.34, 40.0})
        {
            const Chanspec cs = bw == 20   ? Chanspec::make(44, 20)
                                : bw == 40 ? Chanspec::make(46, 40)
                                           : Chanspec::make(42, 80);
            std::vector<std::complex<float>> csi;
            synth.synthesize(
                {planeWave(0.4, 0.0, length)}, {&kSingle, 0.0, 1}, {&kSingle, 0.0, 1}, cs, csi);
            const auto& ks = dataSubcarriers(bw);
            // Unwrap along k and fit a line by least squares.
            double prev = std::arg(at(csi, 1, cs.nfft(), 0, 0, ks[0])), offset = 0;
            double sk = 0, sp = 0, skk = 0, skp = 0;
            int lastK = ks[0];
            for (int k : ks)
            {
                double ph = std::arg(at(csi, 1, cs.nfft(), 0, 0, k)) + offset;
                // Steps between neighbours are < π (|slope·Δk| ≤ 2π·312.5 kHz·133 ns·3 < π).
                while (ph - prev > M_PI)
                {
                    ph -= 2 * M_PI;
                    offset -= 2 * M_PI;
                }
                while (ph - prev < -M_PI)
                {
                    ph += 2 * M_PI;
                    offset += 2 * M_PI;
                }
                prev = ph;
                lastK = k;
                sk += k;
                sp += ph;
                skk += double(k) * k;
                skp += k * ph;
            }
            (void)lastK;
            const double n = double(ks.size());
            const double slope = (n * skp - sk * sp) / (n * skk - sk * sk);
            const double estimatedLength =
                -slope / (2 * M_PI * kSubcarrierSpacingHz) * kSpeedOfLight;
            EXPECT_NEAR(estimatedLength, length, 1e-3) << bw << " MHz";
        }
}

// Any multipath, any array, all (stream, chain) pairs (more than one SIMD chunk): the fast
// recurrence equals the model's formula evaluated term by term in double precision.
TEST(CsiPhysics, MultipathSumMatchesDirectFormula)
{
    CsiSynthesizer synth;
    const AntennaArray ap = makeArray({{0, -0.039}, {0.01, -0.013}, {0, 0.013}, {-0.02, 0.039}});
    const AntennaArray rx8 = makeArray(
        {{0, 0},
         {0, 0.026},
         {0, 0.052},
         {0, 0.078},
         {0.03, 0},
         {0.03, 0.026},
         {0.03, 0.052},
         {0.03, 0.078}});
    std::vector<PropagationPath> paths;
    for (int p = 0; p < 9; ++p)
    {
        auto path = planeWave(-2.5 + 0.6 * p, 1.1 - 0.37 * p, 3.0 + 2.3 * p, 1e-3 / (1 + p));
        path.gain *= std::polar(1.0, 0.9 * p);
        paths.push_back(path);
    }
    for (const auto& [rxArray, nTx] : std::vector<std::pair<const AntennaArray*, unsigned>>{
             {&kRtAc86u, 4}, {&rx8, 3}, {&kSquare, 1}})
        for (const Chanspec cs :
             {Chanspec::make(155, 80), Chanspec::make(6, 20), Chanspec::make(38, 40)})
        {
            const unsigned nRx = unsigned(rxArray->size()), nfft = cs.nfft();
            const double rxYaw = 0.3, txYaw = -1.2;
            std::vector<std::complex<float>> csi;
            synth.synthesize(paths, {rxArray, rxYaw, nRx}, {&ap, txYaw, nTx}, cs, csi);
            ASSERT_EQ(csi.size(), size_t(nTx) * nRx * nfft);
            const int edge = CsiSynthesizer::occupiedEdge(cs.bandwidthMHz);
            double worst = 0, scale = 0;
            for (unsigned m = 0; m < nTx; ++m)
                for (unsigned i = 0; i < nRx; ++i)
                    for (int k = -int(nfft / 2); k < int(nfft / 2); ++k)
                    {
                        std::complex<double> expected = 0;
                        if (std::abs(k) <= edge)
                            for (const auto& p : paths)
                            {
                                const double f = subcarrierFrequencyHz(cs, k);
                                const double ta = p.arrival_rad - rxYaw,
                                             td = p.departure_rad - txYaw;
                                const auto& a = rxArray->elements[i];
                                const auto& b = ap.elements[m];
                                const double phase = -2 * M_PI * f * p.delay_s +
                                                     2 * M_PI * f / kSpeedOfLight *
                                                         (a.x * std::cos(ta) + a.y * std::sin(ta)) +
                                                     2 * M_PI * f / kSpeedOfLight *
                                                         (b.x * std::cos(td) + b.y * std::sin(td));
                                expected += p.gain * std::polar(1.0, phase);
                            }
                        worst = std::max(worst, std::abs(at(csi, nRx, nfft, m, i, k) - expected));
                        scale = std::max(scale, std::abs(expected));
                    }
            EXPECT_LT(worst / scale, 1e-4) << cs.asString() << " " << nTx << "x" << nRx;
        }
}
