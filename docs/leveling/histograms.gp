# Pitch-error histograms of the seed-000 Monte Carlo (like the seed's figures 2 and 3), one
# PNG per method, from the per-run errors that `navtwin level-mc --errors_csv` writes.
# Each histogram (bins of 0.1 deg, same axis for every method) is drawn with the normal
# density of the same RMS for comparison (the seed notes that the plain mean's error is
# not Gaussian and the period average's is).
# Usage: gnuplot -e "csv='errors.csv'; outdir='docs/leveling'" docs/leveling/histograms.gp
# (optional: tag='_xyz' is appended to the file names, for other configurations).
# (docs/leveling/histograms.sh runs the experiment and this script.)
if (!exists("csv")) csv = 'errors.csv'
if (!exists("outdir")) outdir = '.'
if (!exists("tag")) tag = ''

set datafile separator ','
set datafile columnheaders
set terminal pngcairo size 800,500 font 'sans,11' noenhanced
set style fill solid 0.5 border -1
limit = 8.0  # deg; the axis shows [-limit, limit]
set xrange [-limit:limit]
set xlabel 'pitch error (deg)'
set ylabel 'runs per 0.1 deg bin'
set grid
set key top right

width = 0.1
bin(x) = width * (floor(x / width) + 0.5)
normal(x, s, n) = n * width * exp(-0.5 * (x / s)**2) / (s * sqrt(2 * pi))

do for [method in "plain_mean period_average batch"] {
  col = method . '_pitch_deg'
  stats csv using (column(col)) nooutput
  runs = STATS_records
  rms = sqrt(STATS_sumsq / runs)
  biggest = (abs(STATS_min) > abs(STATS_max)) ? abs(STATS_min) : abs(STATS_max)
  stats csv using (abs(column(col)) > limit ? 1 : 0) nooutput
  outside = STATS_sum
  set output outdir . '/pitch_error_' . method . tag . '.png'
  set title sprintf("%s: pitch error of %d runs\nRMS %.4f deg, max |error| %.2f deg, %d runs beyond the axis", \
                    method, runs, rms, biggest, outside)
  plot csv using (bin(column(col))):(1.0) smooth frequency with boxes lc rgb '#4477aa' title 'runs', \
       normal(x, rms, runs) with lines lw 2 lc rgb '#cc3311' title 'normal, same RMS'
  unset output
}
