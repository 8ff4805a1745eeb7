#!/bin/sh
# The HT-LTF and STBC-HT-LTF [imag, real] pairs of every CSI_DATA line (entries 64..127 and
# 128..191 of the 384-value buffer of an HT20 STBC packet without secondary channel), as
# ESP-IDF wrote them; field is 1 for the HT-LTF, 2 for the STBC-HT-LTF.
awk -F'[' 'BEGIN{print "line,field,subcarrier_raw_index,imag,real"}
  /^CSI_DATA/{n=split($2,v,/[ \]]+/); j=0
    for(i=1;i<=n && j<384;i++){ if (v[i]=="") continue; val[j++]=v[i] }
    for(f=1;f<=2;f++) for(s=0;s<64;s++)
      printf "%d,%d,%d,%d,%d\n", NR-1, f, s, val[128*f+2*s], val[128*f+2*s+1]}' "${1:-csi_data.csv}"
