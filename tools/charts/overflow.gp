# tools/charts/overflow.gp — largest scene extent a fixed format sI.F holds.
#   gnuplot -e "in='stability_overflow.csv'; out='x.png'; note='...'" tools/charts/overflow.gp
set terminal pngcairo size 900,600 font ',10'
set output out
set datafile separator ','
set title 'Overflow boundary: largest sphere distance each fixed format s{I}.{F} holds'
set xlabel 'integer bits I'
set ylabel 'scene extent D (radii)'
set logscale y 2
set grid
set key top left box
set bmargin 6
if (strlen(note) > 0) set label 1 note at screen 0.02, screen 0.03 left font ',8'
series(form) = sprintf("< awk -F, '$3 == \"%s\"' '%s'", form, in)
plot series('naive') using 1:4 with linespoints lw 2 pt 7 title 'naive: no overflow flag', \
     series('hb') using 1:4 with linespoints lw 2 pt 5 title 'Hearn-Baker: no overflow flag', \
     series('naive') using 1:5 with linespoints lw 1 dt 2 pt 6 title 'naive: all rays right', \
     series('hb') using 1:5 with linespoints lw 1 dt 2 pt 4 title 'Hearn-Baker: all rays right', \
     2**(x/2.0) with lines lc rgb 'gray' dt 3 title '2^{I/2}', \
     2**x with lines lc rgb 'black' dt 3 title '2^I'
