/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sim/CsiSynthesizer.h>

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace mrpt_wifi::sim
{
int CsiSynthesizer::occupiedEdge(unsigned bandwidthMHz)
{
    switch (bandwidthMHz)
    {
        case 20:
            return 28;
        case 40:
            return 58;
        case 80:
            return 122;
        case 160:
            return 250;
        default:
            throw std::invalid_argument(
                "no occupied-band table for " + std::to_string(bandwidthMHz) + " MHz");
    }
}

namespace
{
/** The angle of e^{-j2π·cycles} in [−2π, 0]: the (possibly large) number of cycles is reduced
 *  in double precision first, so that float keeps the fraction that matters. */
float reducedAngle(double cycles)
{
    const double frac = cycles - std::floor(cycles);
    return float(-2.0 * M_PI * frac);
}

/** Eight float lanes: one AVX register, or two SSE ones. Loaded from and added to any float
 *  address by memcpy, which compilers turn into unaligned vector moves (an under-aligned vector
 *  typedef is honoured by GCC, not by clang: its aligned moves faulted). Always inlined and
 *  by reference: a vector passed by value would depend on the ISA of each target clone. */
typedef float Lanes8 __attribute__((vector_size(32)));
constexpr unsigned kLanes = 8;
__attribute__((always_inline)) inline void load8(Lanes8& v, const float* p)
{
    std::memcpy(&v, p, sizeof v);
}
__attribute__((always_inline)) inline void addTo8(float* p, const Lanes8& v)
{
    Lanes8 sum;
    load8(sum, p);
    sum += v;
    std::memcpy(p, &sum, sizeof sum);
}

/** The hot loop, for one chunk of 8 (stream, chain) pairs: acc[b][lane] += Σ_p z_p · step_p^b.
 *  Two paths advance together so that two independent recurrences hide each other's latency.
 *  Built for AVX2 and for the baseline, picked at load time by the CPU. */
__attribute__((target_clones("avx2", "default"))) void accumulateChunk(
    unsigned nPaths, unsigned nBins, const float* z0Re, const float* z0Im, const float* stepRe,
    const float* stepIm, float* accRe, float* accIm)
{
    unsigned p = 0;
    for (; p + 1 < nPaths; p += 2)
    {
        Lanes8 ar, ai, br, bi, sar, sai, sbr, sbi;
        load8(ar, z0Re + p * kLanes), load8(ai, z0Im + p * kLanes);
        load8(br, z0Re + (p + 1) * kLanes), load8(bi, z0Im + (p + 1) * kLanes);
        load8(sar, stepRe + p * kLanes), load8(sai, stepIm + p * kLanes);
        load8(sbr, stepRe + (p + 1) * kLanes), load8(sbi, stepIm + (p + 1) * kLanes);
        for (unsigned b = 0; b < nBins; ++b)
        {
            addTo8(accRe + b * kLanes, ar + br);
            addTo8(accIm + b * kLanes, ai + bi);
            const Lanes8 nar = ar * sar - ai * sai;
            ai = ar * sai + ai * sar;
            ar = nar;
            const Lanes8 nbr = br * sbr - bi * sbi;
            bi = br * sbi + bi * sbr;
            br = nbr;
        }
    }
    for (; p < nPaths; ++p)
    {
        Lanes8 ar, ai, sar, sai;
        load8(ar, z0Re + p * kLanes), load8(ai, z0Im + p * kLanes);
        load8(sar, stepRe + p * kLanes), load8(sai, stepIm + p * kLanes);
        for (unsigned b = 0; b < nBins; ++b)
        {
            addTo8(accRe + b * kLanes, ar);
            addTo8(accIm + b * kLanes, ai);
            const Lanes8 nar = ar * sar - ai * sai;
            ai = ar * sai + ai * sar;
            ar = nar;
        }
    }
}
}  // namespace

void CsiSynthesizer::synthesize(
    const std::vector<PropagationPath>& paths, const ArrayPlacement& rx, const ArrayPlacement& tx,
    const Chanspec& chanspec, std::vector<std::complex<float>>& out)
{
    const unsigned nRx = rx.elementsUsed, nTx = tx.elementsUsed;
    if (!rx.array || !tx.array || nRx == 0 || nTx == 0 || nRx > rx.array->size() ||
        nTx > tx.array->size())
        throw std::invalid_argument("CsiSynthesizer: inconsistent array placement");
    const unsigned nfft = chanspec.nfft();
    const int edge = occupiedEdge(chanspec.bandwidthMHz);
    const unsigned nBins = unsigned(2 * edge + 1);
    const unsigned nPairs = nRx * nTx;
    const unsigned nChunks = (nPairs + kLanes - 1) / kLanes;
    const unsigned Q = nChunks * kLanes;  // pairs padded to whole chunks
    const unsigned nPaths = unsigned(paths.size());

    // Layouts: z0/step [chunk][path][lane], acc [chunk][bin][lane]; pair q = chunk·8 + lane.
    // Per (path, pair): complex value at the lowest occupied subcarrier and the per-subcarrier
    // step, both from the pair's effective delay τ − (a_i·u_arr)/c − (b_m·u_dep)/c.
    z0Re_.assign(size_t(nPaths) * Q, 0.f);
    z0Im_.assign(size_t(nPaths) * Q, 0.f);
    stepRe_.assign(size_t(nPaths) * Q, 1.f);
    stepIm_.assign(size_t(nPaths) * Q, 0.f);
    const double f0 = subcarrierFrequencyHz(chanspec, -edge);
    const double df = kSubcarrierSpacingHz;

    // Phasors per path, factored: path delay (start, step), then per rx element and per tx
    // element the advance of that element along the ray (start, step). Their angles are
    // reduced in double precision, then all sines/cosines are taken at once (vectorised).
    const unsigned perPath = 2 + 2 * nRx + 2 * nTx;
    angles_.resize(Eigen::Index(nPaths) * perPath);
    for (unsigned p = 0; p < nPaths; ++p)
    {
        const auto& path = paths[p];
        const double thRx = path.arrival_rad - rx.yaw_rad;
        const double thTx = path.departure_rad - tx.yaw_rad;
        const double cRx = std::cos(thRx), sRx = std::sin(thRx);
        const double cTx = std::cos(thTx), sTx = std::sin(thTx);
        float* ang = angles_.data() + size_t(p) * perPath;
        ang[0] = reducedAngle(f0 * path.delay_s);
        ang[1] = reducedAngle(df * path.delay_s);
        for (unsigned i = 0; i < nRx; ++i)
        {
            const auto& e = rx.array->elements[i];
            const double advance_s = (e.x * cRx + e.y * sRx) / kSpeedOfLight;
            ang[2 + 2 * i] = reducedAngle(-f0 * advance_s);
            ang[3 + 2 * i] = reducedAngle(-df * advance_s);
        }
        for (unsigned m = 0; m < nTx; ++m)
        {
            const auto& e = tx.array->elements[m];
            const double advance_s = (e.x * cTx + e.y * sTx) / kSpeedOfLight;
            ang[2 + 2 * nRx + 2 * m] = reducedAngle(-f0 * advance_s);
            ang[3 + 2 * nRx + 2 * m] = reducedAngle(-df * advance_s);
        }
    }
    cosines_ = angles_.cos();
    sines_ = angles_.sin();

    for (unsigned p = 0; p < nPaths; ++p)
    {
        const float* c = cosines_.data() + size_t(p) * perPath;
        const float* sn = sines_.data() + size_t(p) * perPath;
        auto phasor = [&](unsigned j) { return std::complex<double>(c[j], sn[j]); };
        const std::complex<double> base0 = paths[p].gain * phasor(0);
        const std::complex<double> baseStep = phasor(1);
        for (unsigned m = 0; m < nTx; ++m)
        {
            const std::complex<double> tz = base0 * phasor(2 + 2 * nRx + 2 * m);
            const std::complex<double> ts = baseStep * phasor(3 + 2 * nRx + 2 * m);
            for (unsigned i = 0; i < nRx; ++i)
            {
                const unsigned q = m * nRx + i;
                const std::complex<double> z = tz * phasor(2 + 2 * i);
                const std::complex<double> st = ts * phasor(3 + 2 * i);
                const size_t at = (size_t(q / kLanes) * nPaths + p) * kLanes + q % kLanes;
                z0Re_[at] = float(z.real());
                z0Im_[at] = float(z.imag());
                stepRe_[at] = float(st.real());
                stepIm_[at] = float(st.imag());
            }
        }
    }

    accRe_.assign(size_t(nBins) * Q, 0.f);
    accIm_.assign(size_t(nBins) * Q, 0.f);
    for (unsigned c = 0; c < nChunks; ++c)
    {
        const size_t zAt = size_t(c) * nPaths * kLanes, accAt = size_t(c) * nBins * kLanes;
        accumulateChunk(
            nPaths, nBins, z0Re_.data() + zAt, z0Im_.data() + zAt, stepRe_.data() + zAt,
            stepIm_.data() + zAt, accRe_.data() + accAt, accIm_.data() + accAt);
    }

    // [chunk][bin][lane] → [tx][rx][bin] over all NFFT bins; guard bins stay zero.
    out.assign(size_t(nPairs) * nfft, std::complex<float>(0.f, 0.f));
    const unsigned firstBin = subcarrierToBin(-edge, nfft);
    for (unsigned q = 0; q < nPairs; ++q)
    {
        std::complex<float>* dst = out.data() + size_t(q) * nfft + firstBin;
        const size_t base = size_t(q / kLanes) * nBins * kLanes + q % kLanes;
        for (unsigned b = 0; b < nBins; ++b)
            dst[b] = {accRe_[base + size_t(b) * kLanes], accIm_[base + size_t(b) * kLanes]};
    }
}

}  // namespace mrpt_wifi::sim
