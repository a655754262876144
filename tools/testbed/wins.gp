# tools/testbed/wins.gp — "where each method wins": the fastest method (modelled seconds) at
# each Ethernet bandwidth × object count, the paper's network marked. Called by
# tools/testbed/charts.sh and tools/testbed/future.sh with in= (CSV:
# ethernet_bps,objects,winner 1..5,...), out=, paperbw= (the testbed's own bandwidth, marked),
# note=, and optionally ttl= (the title) and paperlabel= (the mark's label).
set terminal pngcairo size 900,600 font ',10'
set output out
set datafile separator ','
if (!exists('ttl')) ttl = 'Where each method wins (fastest in modelled 1992 seconds)'
if (!exists('paperlabel')) paperlabel = "the paper's 10 Mbit/s"
set title ttl noenhanced
set xlabel 'Ethernet bandwidth (bit/s)'
set ylabel 'objects'
set logscale x 10
set logscale y 2
set offsets graph 0.1, graph 0.1, graph 0.1, graph 0.1
set bmargin 7
set grid
set key outside right top
set palette defined (1 'gray40', 2 'dark-orange', 3 'royalblue', 4 'forest-green', 5 'purple')
set cbrange [1:5]
unset colorbox
# The note wrapped at its last '; ' before 140 characters (about what 900 px hold at 8 pt),
# so no line is cut at the right edge.
brk(s, i) = i < 2 ? 0 : (substr(s, i - 1, i) eq '; ' ? i : brk(s, i - 1))
b = strlen(note) > 140 ? brk(note, 140) : 0
wrapped = b > 0 ? substr(note, 1, b - 1) . "\n" . substr(note, b + 1, strlen(note)) : note
set label 1 wrapped at screen 0.02, screen 0.05 left font ',8' noenhanced
set arrow from paperbw, graph 0 to paperbw, graph 1 nohead dt 2 lw 2 lc 'red'
set label 2 paperlabel at paperbw, graph 1.02 center tc 'red'
names = 'sequential SIMD/seq distributed heterogeneous all-on-array'
plot in using 1:2:3 every ::1 with points pt 5 ps 5 lc palette notitle, \
     in using 1:2:(word(names, int($3))) every ::1 with labels offset 0,2 notitle, \
     1/0 with points pt 5 ps 2 lc rgb 'gray40' title 'sequential', \
     1/0 with points pt 5 ps 2 lc rgb 'dark-orange' title 'SIMD/sequential', \
     1/0 with points pt 5 ps 2 lc rgb 'royalblue' title 'distributed', \
     1/0 with points pt 5 ps 2 lc rgb 'forest-green' title 'heterogeneous', \
     1/0 with points pt 5 ps 2 lc rgb 'purple' title 'all rays on the array'
