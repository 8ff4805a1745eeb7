#!/usr/bin/env python3
"""Independent reading of a WSR Toolbox .dat (Intel 5300 records + an 18-byte trailer), used to
derive the expected values of CsiDecoders.RealWsrRecordingIsReadWithItsTrailer. Written from
the record layout alone (read_bfee.c's bit packing; the trailer: uint32 s, uint32 µs, 6-byte
MAC, uint32 frame counter, little-endian), sharing no code with the C++ decoder.

    read_wsr_records.py FILE.dat   -> counts per sender, then the first and last record
"""
import collections
import struct
import sys


def records(path):
    data = open(path, 'rb').read()
    pos = 0
    while pos + 3 <= len(data):
        length = struct.unpack('>H', data[pos:pos + 2])[0]
        if pos + 2 + length > len(data):
            print('truncated record at byte', pos)
            return
        if data[pos + 2] == 0xBB:
            yield data[pos + 3:pos + 2 + length]
        pos += 2 + length


def decode(rec):
    n_rx, n_tx = rec[8], rec[9]
    sec, usec = struct.unpack('<II', rec[20:28])
    mac = ':'.join('%02x' % b for b in rec[28:34])
    count = struct.unpack('<I', rec[34:38])[0]
    payload = rec[38:]
    bits = int.from_bytes(payload, 'little')  # bit i of the stream = bit i of this integer
    csi = [[None] * 30 for _ in range(n_rx * n_tx)]
    index = 0
    for s in range(30):
        index += 3
        for j in range(n_rx * n_tx):
            re = (bits >> index) & 0xFF
            im = (bits >> (index + 8)) & 0xFF
            csi[j][s] = (re - 256 if re > 127 else re, im - 256 if im > 127 else im)
            index += 16
    return sec + usec * 1e-6, mac, count, n_rx, n_tx, csi


if __name__ == '__main__':
    decoded = [decode(r) for r in records(sys.argv[1])]
    print('records', len(decoded))
    print('per sender', sorted(collections.Counter(d[1] for d in decoded).items()))
    for d in (decoded[0], decoded[-1]):
        t, mac, count, n_rx, n_tx, csi = d
        print('time %.6f mac %s count %d nrx %d ntx %d' % (t, mac, count, n_rx, n_tx))
        print('  rx0', csi[0])
