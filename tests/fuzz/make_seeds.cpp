// Writes a seed corpus for fuzz_nexmon_assembler: valid frames of every header variant and
// bandwidth, in the fuzzer's record format. Usage: fuzz_make_seeds DIR
#include <mrpt_wifi/sensor/NexmonFormat.h>

#include <fstream>
#include <iostream>

#include "SyntheticCsi.h"

using namespace mrpt_wifi;

int main(int argc, char** argv)
{
    if (argc != 2)
    {
        std::cerr << "usage: fuzz_make_seeds DIR\n";
        return 1;
    }
    int n = 0;
    for (auto variant :
         {NexmonHeaderVariant::Nexmon, NexmonHeaderVariant::NexmonLegacy,
          NexmonHeaderVariant::UbiLocate})
        for (unsigned bw : {20u, 40u, 80u})
        {
            std::ofstream f(
                std::string(argv[1]) + "/seed_" + std::to_string(n++), std::ios::binary);
            f.put(char(uint8_t(variant) + 1));
            for (uint16_t seq = 0; seq < 2; ++seq)
                for (const auto& d : nexmon::encodeFrame(
                         *test::syntheticFrame(2, 2, bw, seq, "02:00:00:00:00:01", variant)))
                {
                    f.put(char(d.size() & 0xFF));
                    f.put(char(d.size() >> 8));
                    f.write(reinterpret_cast<const char*>(d.data()), std::streamsize(d.size()));
                }
        }
    std::cout << "wrote " << n << " seeds to " << argv[1] << "\n";
    return 0;
}
