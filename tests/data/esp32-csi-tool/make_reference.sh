#!/bin/sh
# An independent reading of the rows with awk: per CSI_DATA row its mac, rssi, noise_floor,
# channel, local_timestamp and len, and the 64 [imag, real] pairs the bracket holds.
#   make_reference.sh [IN.csv]   (writes the two reference files next to it)
in=${1:-example_data.first20.csv}
awk -F, 'BEGIN{print "row,mac,rssi,noise_floor,channel,local_timestamp,len"}
  /^CSI_DATA/{printf "%d,%s,%s,%s,%s,%s,%s\n", n++, $3, $4, $15, $17, $19, $25}' "$in" \
  > "${in%.csv}.meta.reference.csv"
awk -F'[' 'BEGIN{print "row,entry,imag,real"}
  /^CSI_DATA/{m=split($2,v,/[ \]]+/); j=0
    for(i=1;i<=m;i++){ if (v[i]=="") continue; val[j++]=v[i] }
    for(e=0;e<j/2;e++) printf "%d,%d,%d,%d\n", n, e, val[2*e], val[2*e+1]; n++}' "$in" \
  > "${in%.csv}.reference.csv"
