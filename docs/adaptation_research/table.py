import re,glob,sys
def parse(f):
    L=[l for l in open(f) if l.startswith('SUMMARY')]
    if not L: return None
    return dict(kv.split('=',1) for kv in L[0].split()[1:])
pat=sys.argv[1] if len(sys.argv)>1 else 'full_*'
print('| run | fault | in bounds (min, max/bound) | fr rms err last 20 s / 60 s [N m] | worst 60 s window after 120 s x/y/z mm, phx/phy/phz deg | first 20 min x/y/z | last 20 min x/y/z | windows over T.I | vis1 / sti3 final |')
print('|---|---|---|---|---|---|---|---|---|')
for f in sorted(glob.glob('out8/'+pat+'.txt')):
    d=parse(f)
    if not d: continue
    n=f.split('/')[-1][:-4]
    print(f"| {n} | {d['fault']} | {'yes' if d['in_bounds']=='1' else 'NO'} ({d['theta_min']}, {d['theta_max/bound']}) | {d['fr_rms_err20']} / {d['fr_rms_err60']} | {d['worst']} | {d['first20']} | {d['last20']} | {d['windows_over_T1']} | {d['vis1']} / {d['sti3']} |")
