/* mrpt_wifi — deterministic CSI frames for unit tests. */
#pragma once

#include <mrpt_wifi/obs/CObservationWiFiCSI.h>

#include <cmath>

namespace mrpt_wifi::test
{
/** A full frame whose every bin is non-zero and distinct per (tx, rx, bin), with magnitudes
 * spread over several binary orders like real CSI. */
inline CObservationWiFiCSI::Ptr syntheticFrame(
    unsigned nTx, unsigned nRx, unsigned bandwidthMHz = 80, uint16_t seq = 100,
    const char* mac = "00:12:34:56:78:9b",
    NexmonHeaderVariant variant = NexmonHeaderVariant::Nexmon)
{
    auto o = CObservationWiFiCSI::Create();
    o->transmitter = MacAddress::fromString(mac);
    o->sequenceNumber = seq;
    o->rssi_dBm = -48;
    o->chanspec = Chanspec::make(
        bandwidthMHz == 80   ? 155
        : bandwidthMHz == 40 ? 151
                             : 149,
        bandwidthMHz);
    o->chipId = 0x006a;
    o->headerVariant = variant;
    o->resize(nTx, nRx, o->chanspec.nfft());
    for (unsigned tx = 0; tx < nTx; ++tx)
        for (unsigned rx = 0; rx < nRx; ++rx)
        {
            o->setPresent(tx, rx);
            for (unsigned b = 0; b < o->nfft(); ++b)
            {
                const float mag = 300.0f * (1.0f + 0.5f * std::sin(0.07f * b + tx)) * float(1 + rx);
                o->at(tx, rx, b) = std::polar(mag, 0.11f * b + 0.7f * rx - 0.3f * tx + 0.01f * seq);
            }
        }
    return o;
}
}  // namespace mrpt_wifi::test
