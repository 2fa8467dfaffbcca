#!/usr/bin/env python3
"""Every relative link in the repository's Markdown files points to a file that exists.

Run from the repository root: `python3 scripts/check_links.py` (exit 1 on a broken link)."""
import re,os,subprocess,sys
files=subprocess.run(['git','ls-files','*.md'],capture_output=True,text=True).stdout.split()+[f for f in subprocess.run(['git','ls-files','--others','--exclude-standard'],capture_output=True,text=True).stdout.split() if f.endswith('.md')]
bad=0
for f in sorted(set(files)):
    s=open(f).read()
    s=re.sub(r'```.*?```','',s,flags=re.S)
    for m in re.finditer(r'\]\(([^)\s]+)\)',s):
        t=m.group(1)
        if re.match(r'[a-z]+://|mailto:|#',t): continue
        p=t.split('#')[0]
        if not os.path.exists(os.path.normpath(os.path.join(os.path.dirname(f),p))):
            print(f'{f}: broken link {t}'); bad+=1
print('broken links:',bad); sys.exit(1 if bad else 0)
