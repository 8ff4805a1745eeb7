function y = db(x, kind)
  % MATLAB Signal Processing Toolbox db(): 10*log10 for 'power', 20*log10 otherwise.
  if nargin > 1 && any(strcmpi(kind, {'pow','power'}))
    y = 10*log10(x);
  else
    y = 20*log10(abs(x));
  end
end
