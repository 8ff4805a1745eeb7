#!/usr/bin/env python3
"""Writes a WSR dataset location's true transmitter positions (groundtruth_positions.json) as a
TransmitterMap YAML for `wifi-sar --truth`, with the MACs of the dataset's config
(config_files/dataset.json: input_TX_channel_csi_fn.value.txN.mac_id).

    wsr_peers.py groundtruth_positions.json dataset.json > peers.yaml
"""
import json
import sys

truth = json.load(open(sys.argv[1]))['true_tx_positions']['value']
macs = json.load(open(sys.argv[2]))['input_TX_channel_csi_fn']['value']
print('# from %s (true positions, OptiTrack frame) and %s (MACs)' % (sys.argv[1], sys.argv[2]))
print('transmitters:')
for name, entry in sorted(truth.items()):
    if name not in macs:
        continue
    p = entry['position']
    if p['x'] == 0 and p['y'] == 0 and p['z'] == 0:
        continue  # placeholder entries of the dataset
    print("  - name: %s\n    mac: '%s'\n    position: [%.4f, %.4f]" %
          (name, macs[name]['mac_id'].lower(), p['x'], p['y']))
