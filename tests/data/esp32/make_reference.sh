#!/bin/sh
# The first 64 [imag, real] pairs (the L-LTF) of every CSI_DATA line, as ESP-IDF wrote them.
awk -F'[' 'BEGIN{print "line,subcarrier_raw_index,imag,real"}
  /^CSI_DATA/{n=split($2,v,/[ \]]+/); j=0
    for(i=1;i<=n && j<128;i++){ if (v[i]=="") continue; val[j++]=v[i] }
    for(s=0;s<64;s++) printf "%d,%d,%d,%d\n", NR-1, s, val[2*s], val[2*s+1]}' "${1:-csi_data.csv}"
