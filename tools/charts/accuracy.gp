# tools/charts/accuracy.gp — speed against accuracy for one accuracy measure.
#   gnuplot -e "in='accuracy.csv'; out='x.png'; ttl='...'; xl='...'; xcol=N; note='...';
#               logx=1; empty=0" tools/charts/accuracy.gp
# accuracy.csv columns: kind,frac_bits,cycles,host_s,pct_wrong,t_err_max,t_err_mean,psnr,planned
# kind is 'fixed' (the SIMD primary pass at --frac-bits N), 'float32' or 'float64' (the
# sequential host tracers). Fixed rows: cycles on the left axis, emulator host seconds on
# the right; the float tracers have no cycles and appear on the host-time axis only.
set terminal pngcairo size 900,650 font ',10'
set output out
set datafile separator ','
set datafile missing 'NaN'
set title ttl
set xlabel xl
set ylabel 'cycles per primary pass (modelled machine)'
set y2label 'host seconds (emulator, or host float tracer)'
set ytics nomirror
set y2tics
set logscale y
set logscale y2
if (logx) set logscale x
set grid
set key tmargin horizontal maxcols 3 box font ',9'
set bmargin 9
if (strlen(note) > 0) set label 1 note at screen 0.02, screen 0.08 left font ',8' noenhanced
if (exists('note2') && strlen(note2) > 0) set label 3 note2 at screen 0.02, screen 0.05 left font ',8' noenhanced
if (exists('note3') && strlen(note3) > 0) set label 4 note3 at screen 0.02, screen 0.02 left font ',8' noenhanced
if (empty) {
  set xrange [0:1]; set yrange [1:2]; set y2range [1:2]
  set label 2 'no data: the SIMD method (--frac-bits, accuracy) is not available yet' at graph 0.5, graph 0.5 center
  plot 1.5 notitle lc rgb 'white'
} else {
  plot in using (strcol(1) eq 'fixed' && column(9) == 0 ? column(xcol) : NaN):3 with linespoints lw 2 pt 7 title 'SIMD cycles (fixed, by fraction bits)', \
       ''  using (strcol(1) eq 'fixed' ? column(xcol) : NaN):3:(column(2) == column(2) ? sprintf('%d', column(2)) : 'planned') with labels offset 0,1 font ',8' notitle, \
       ''  using (strcol(1) eq 'fixed' && column(9) == 0 ? column(xcol) : NaN):4 axes x1y2 with linespoints lw 1 dt 2 pt 6 title 'SIMD emulator host time', \
       ''  using (strcol(1) eq 'fixed' && column(9) == 1 ? column(xcol) : NaN):3 with points pt 3 ps 3 lc rgb 'red' title "planner's choice", \
       ''  using (strcol(1) eq 'float32' ? column(xcol) : NaN):4 axes x1y2 with points pt 5 ps 2 title 'seq float32 (host time)', \
       ''  using (strcol(1) eq 'float64' ? column(xcol) : NaN):4 axes x1y2 with points pt 9 ps 2 title 'seq float64 (host time)'
}
