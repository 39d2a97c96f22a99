"""The tire-fbs dashboard (Panel + Bokeh + param).

Serve it with ``panel serve app/main.py`` (or ``scripts/serve.sh``). State lives in
:mod:`app.state`, the cached calls into :mod:`fbs_core` in :mod:`app.compute`, the views in
:mod:`app.views`; :func:`app.main.create_app` assembles one session's page.
"""
