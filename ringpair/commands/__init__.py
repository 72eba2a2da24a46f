"""The commands of ``ringpair``, one module each; :mod:`ringpair.cli` registers them.

Shared arguments, options, loaders and errors are in :mod:`ringpair.options`. A command
imports the optimisation, CAD and plotting packages (and the modules here that use them)
inside its body, so that ``ringpair --help`` and the light commands start without them.
"""
