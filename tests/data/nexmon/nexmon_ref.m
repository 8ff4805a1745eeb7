% Reference decode of Nexmon CSI captures with nexmon_csi's MATLAB logic (csireader.m):
% int16 typecast (4339, 43455c0) or the unpack_float MEX (4358: format 0, 4366c0: format 1).
function nexmon_ref(pcapfile, chip, outfile)
  f = fopen(pcapfile, 'r'); bytes = fread(f, Inf, 'uint8=>uint8'); fclose(f);
  pos = 25; k = 0; out = fopen(outfile, 'w');
  fprintf(out, 'datagram,index,re,im\n');
  while pos + 16 <= numel(bytes)
    incl = double(typecast(bytes(pos+8:pos+11), 'uint32'));
    pkt = bytes(pos+16:pos+16+incl-1);
    pos = pos + 16 + incl;
    payload = pkt(43:end);              % Ethernet 14 + IPv4 20 + UDP 8
    nfft = (numel(payload) - 18) / 4;
    H = typecast(payload(19:end), 'uint32');
    if any(strcmp(chip, {'4339', '43455c0'}))
      Hout = double(typecast(H, 'int16'));
    elseif strcmp(chip, '4358')
      Hout = double(unpack_float(int32(0), int32(nfft), H));
    else
      Hout = double(unpack_float(int32(1), int32(nfft), H));
    end
    Hout = reshape(Hout, 2, []).';
    for i = 1:nfft
      fprintf(out, '%d,%d,%.17g,%.17g\n', k, i-1, Hout(i,1), Hout(i,2));
    end
    k = k + 1;
  end
  fclose(out);
end
