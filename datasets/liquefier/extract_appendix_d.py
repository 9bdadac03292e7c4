#!/usr/bin/env python3
# Extracts seed 001 appendix D (frequency-response measurements) into one CSV per experiment.
# Run from datasets/liquefier with the seed text at /work/shared/seeds/001_*.txt (not needed to build or test).
import re, math, glob
txt = open(glob.glob('/work/shared/seeds/001_*.txt')[0]).read()
def arr(name, end):
    i = txt.index(name + '=[[') + len(name) + 1
    j = txt.index(end, i)
    body = txt[i:j]
    out = []
    for m in re.finditer(r'\[([^\[\]]*)\]?', body):
        part = m.group(1).strip().strip(',')
        if not part: continue
        part = re.sub(r'(\d) (\d)', r'\1, \2', part)  # one comma lost in exp. 8 time stamps
        out.append([float(x) for x in part.split(',') if x.strip()])
    return out
ts = arr('timestamps', 'setpointwidth=')
sp = arr('setpointwidth', 'measuredwidth=')
me = arr('measuredwidth', '# Data export')
design = [(1,0.1,2,40),(3,0.08,10,40),(1,0.25,5,40),(2,0.13,40,40),(5,0.05,50,40),(1,0.24,1,40),(1,0.24,100,40),(1,0.24,10,20),(2,0.12,2.5,40),(2,0.12,5,40),(6,0.04,5,72),(3,0.08,40,20)]
assert len(ts)==len(sp)==len(me)==12, (len(ts),len(sp),len(me))
R=30.0
with open('appendix_d/design.csv','w') as f:
    f.write('# Seed 001 Table 4.2 (experiment design) with the sine frequency f = n_sines * v_print / (2 pi R), R = 30 mm (see PROVENANCE.md)\n')
    f.write('experiment,n_sines,amplitude_mm,v_print_mm_s,n_measurements,rotation_time_s,freq_hz\n')
    for k,(N,A,v,n) in enumerate(design):
        assert len(ts[k])==n==len(sp[k])==len(me[k]), (k,len(ts[k]),len(sp[k]),len(me[k]))
        T = 2*math.pi*R/v
        dt = T/n
        assert abs(ts[k][1]-dt) < 0.011 and abs(ts[k][-1]-(n-1)*dt) < 0.011, (k, ts[k][1], dt)
        f.write(f'{k},{N},{A},{v},{n},{T:.6f},{N/T:.8f}\n')
        with open(f'appendix_d/exp_{k:02d}.csv','w') as g:
            g.write(f'# Seed 001 appendix D, experiment {k} (Table 4.2: n_sines={N}, A={A} mm, v_print={v} mm/s); sine frequency {N/T:.8f} Hz\n')
            g.write('time (s),setpoint_width (mm),width (mm)\n')
            for a,b,c in zip(ts[k],sp[k],me[k]):
                g.write(f'{a:g},{b:g},{c:g}\n')
print('8==9 measured', me[8]==me[9], 'setpoint', sp[8]==sp[9], 'time', ts[8]==ts[9])
