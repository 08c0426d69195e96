"""The `lumipose` command: the server's, the client's and the simulator's commands in one tree.

The only package that imports all three; `lumipose_cli.main:main` is the console script.
"""
