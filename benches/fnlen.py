"""Functions at least N lines long (default 120), longest first:
`python3 benches/fnlen.py . 80` from the repository root. BENCHMARKS.md's
function-length scans come from it."""
import re,sys,os
pat=re.compile(r'^(\s*)(pub(\([^)]*\))?\s+)?(const\s+)?(unsafe\s+)?(async\s+)?fn\s+(\w+)')
res=[]
for root,_,files in os.walk(sys.argv[1]):
    if '/target' in root or '/.venv' in root or '/.git' in root: continue
    for f in files:
        if not f.endswith('.rs'): continue
        p=os.path.join(root,f); L=open(p).read().split('\n')
        for i,l in enumerate(L):
            m=pat.match(l)
            if not m: continue
            ind=m.group(1)
            for j in range(i,len(L)):
                if L[j]==ind+'}' : res.append((j-i+1,p,m.group(7)));break
                if j==i and l.rstrip().endswith(';'): break
thr=int(sys.argv[2]) if len(sys.argv)>2 else 120
for n,p,name in sorted(res,reverse=True):
    if n>=thr: print(n,p,name)
