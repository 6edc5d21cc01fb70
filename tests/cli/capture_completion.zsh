#!/usr/bin/zsh -f
# zsh -f capture_completion.zsh SCRIPT LINE...: for each LINE, the matches zsh's completion offers at its end,
# one a line, then "<END>". An interactive zsh runs in a pseudo-terminal (zpty) with SCRIPT sourced after
# compinit; compadd is wrapped to print the matches it is given; each LINE is typed with a TAB, then erased.
# (After github.com/Valodim/zsh-capture-completion.)
zmodload zsh/zpty || exit 2
script=$1; shift
zpty z zsh -f -i
zpty -w z "PROMPT= ; RPROMPT= ; unsetopt zle_bracketed_paste 2>/dev/null"
zpty -w z "autoload -U compinit && compinit -u -D"
zpty -w z "source ${(q)script}"
zpty -w z 'compadd () {
  if [[ ${@[1,(i)(-|--)]} == *-(O|A|D)\ * ]]; then builtin compadd "$@"; return $?; fi
  typeset -a __hits
  builtin compadd -A __hits "$@"
  typeset -i i
  for ((i = 1; i <= $#__hits; i++)); do print -r -- "<MA""TCH>${__hits[$i]}"; done
}'
zpty -w z "zstyle ':completion:*' list-grouped false; zstyle ':completion:*' insert-tab false"
zpty -w z "mark () { print; print '<EN''D>'; BUFFER=; zle reset-prompt }; zle -N mark; bindkey '^X' mark"
for line in "$@"; do
  zpty -n -w z "$line"$'\t'
  zpty -n -w z $'\C-X'
  while zpty -r z chunk; do
    for l in ${(f)chunk}; do
      [[ $l == *'<MATCH>'* ]] && print -r -- ${${l#*<MATCH>}%%$'\r'*}
    done
    [[ $chunk == *'<END>'* ]] && { print '<END>'; break }
  done
done
zpty -d z
