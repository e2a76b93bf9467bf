"""``stereovar completion {bash,zsh,fish}``: the shell code that makes Tab complete the
``stereovar`` command, its groups, options and ``run``'s targets (argcomplete)."""

from __future__ import annotations

import argparse

#: The shells :func:`argcomplete.shellcode` writes code for.
SHELLS = ("bash", "zsh", "fish")


def _cmd_completion(args: argparse.Namespace) -> int:
    import argcomplete

    print(argcomplete.shellcode(["stereovar"], shell=args.shell), end="")
    return 0


def _register_completion(subparsers) -> None:
    completion = subparsers.add_parser(
        "completion",
        help="print the shell code for Tab completion of stereovar",
        description="Print the code that makes your shell complete stereovar's commands, "
        "options and run targets with Tab. Load it in the shell's start-up file, e.g. "
        'eval "$(stereovar completion bash)" in ~/.bashrc (zsh: the same in ~/.zshrc; '
        "fish: stereovar completion fish | source in ~/.config/fish/config.fish).",
    )
    completion.add_argument("shell", choices=SHELLS, help="the shell")
    completion.set_defaults(func=_cmd_completion)
