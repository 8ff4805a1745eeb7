% Reference decode of an Intel 5300 .dat with the CSI Tool's read_bf_file + get_scaled_csi.
function intel_ref(datfile, outfile)
  recs = read_bf_file(datfile);
  out = fopen(outfile, 'w');
  fprintf(out, 'record,tx,rx,subcarrier,re,im,scaled_re,scaled_im\n');
  for r = 1:numel(recs)
    st = recs{r};
    csi = st.csi; sc = get_scaled_csi(st);
    for tx = 1:size(csi,1)
      for rx = 1:size(csi,2)
        for s = 1:30
          fprintf(out, '%d,%d,%d,%d,%.9g,%.9g,%.9g,%.9g\n', r-1, tx-1, rx-1, s-1, ...
                  real(csi(tx,rx,s)), imag(csi(tx,rx,s)), real(sc(tx,rx,s)), imag(sc(tx,rx,s)));
        end
      end
    end
  end
  fclose(out);
end
