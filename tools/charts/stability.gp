# tools/charts/stability.gp — error against distance for a radius-1 sphere (RTG ch. 7).
#   gnuplot -e "in='stability_distance.csv'; out='x.png'; ycol=N; yl='...'; ttl='...';
#               logy=1; note='...'" tools/charts/stability.gp
# One line per (form, format): naive solid, Hearn-Baker dashed.
set terminal pngcairo size 1000,650 font ',10'
set output out
set datafile separator ','
set title ttl
set xlabel 'sphere distance D (radii)'
set ylabel yl
set logscale x 2
set format x '2^{%L}'
if (logy) set logscale y
set grid
set key outside right top box
set bmargin 6
if (strlen(note) > 0) set label 1 note at screen 0.02, screen 0.03 left font ',8'
formats = system("awk -F, 'NR>1{print $3}' " . in . " | awk '!s[$0]++' | tr '\\n' ' '")
# log axes cannot show 0: lift zeros to a floor, stated in the note
floor = logy ? 1e-17 : 0
val(x) = (logy && x <= floor) ? floor : x
series(form, f) = sprintf("< awk -F, '$2 == \"%s\" && $3 == \"%s\"' '%s'", form, f, in)
plot for [i=1:words(formats)] series('naive', word(formats, i)) using 1:(val(column(ycol))) \
       with linespoints lw 2 lc i pt 7 ps 0.6 title 'naive '.word(formats, i), \
     for [i=1:words(formats)] series('hb', word(formats, i)) using 1:(val(column(ycol))) \
       with linespoints lw 2 lc i dt 2 pt 6 ps 0.6 title 'Hearn-Baker '.word(formats, i)
