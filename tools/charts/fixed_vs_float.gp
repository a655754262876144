# tools/charts/fixed_vs_float.gp — fixed against float on the array (tools/charts/fixed_vs_float.sh).
#   gnuplot -e "in='fixed_vs_float.csv'; out='x.png'; xcol=5; xl='...'; note='...'" tools/charts/fixed_vs_float.gp
# columns: kind,label,cycles,host_s,pct_wrong,t_err_max,psnr,grazing,near_tie; kind fixed | float (the
# array: cycles per primary pass, left axis) or seq (host tracers: host seconds, right axis).
set terminal pngcairo size 900,650 font ',10'
set output out
set datafile separator ','
set datafile missing 'NaN'
set title 'Fixed against float on the array: cycles per primary pass against accuracy'
set xlabel xl
set ylabel 'cycles per primary pass (modelled WaveTracer)'
set y2label 'host seconds (sequential tracer, for comparison)'
set ytics nomirror
set y2tics
set logscale y
set logscale y2
set grid
# logx=1: a log x axis with 0 drawn at `floor` (the note says so)
if (!exists('logx')) logx = 0
if (!exists('floor')) floor = 0
if (logx) set logscale x
x(c) = (logx && column(c) <= 0) ? floor : column(c)
set key tmargin horizontal maxcols 2 box font ',9'
set bmargin 6
set label 1 note at screen 0.02, screen 0.03 left font ',8' noenhanced
# hasseq=0: no host tracer has a finite value on this axis (a PSNR of inf is not drawn)
if (!exists('hasseq')) hasseq = 1
if (hasseq) {
  plot in using (strcol(1) eq 'fixed' ? x(xcol) : NaN):3 with linespoints lw 2 pt 7 title 'array, fixed point (label: fraction bits)', \
       ''  using (strcol(1) eq 'fixed' ? x(xcol) : NaN):3:2 with labels offset 0,1 font ',8' notitle noenhanced, \
       ''  using (strcol(1) eq 'float' ? x(xcol) : NaN):3 with linespoints lw 2 pt 5 title 'array, bit-serial float (label: format)', \
       ''  using (strcol(1) eq 'float' ? x(xcol) : NaN):3:2 with labels offset 0,-1 font ',8' notitle noenhanced, \
       ''  using (strcol(1) eq 'seq' ? x(xcol) : NaN):4 axes x1y2 with points pt 9 ps 2 title 'host seq float32 / float64 (host seconds)', \
       ''  using (strcol(1) eq 'seq' ? x(xcol) : NaN):4:2 axes x1y2 with labels offset 0,1 font ',8' notitle noenhanced
} else {
  plot in using (strcol(1) eq 'fixed' ? x(xcol) : NaN):3 with linespoints lw 2 pt 7 title 'array, fixed point (label: fraction bits)', \
       ''  using (strcol(1) eq 'fixed' ? x(xcol) : NaN):3:2 with labels offset 0,1 font ',8' notitle noenhanced, \
       ''  using (strcol(1) eq 'float' ? x(xcol) : NaN):3 with linespoints lw 2 pt 5 title 'array, bit-serial float (label: format)', \
       ''  using (strcol(1) eq 'float' ? x(xcol) : NaN):3:2 with labels offset 0,-1 font ',8' notitle noenhanced
}
