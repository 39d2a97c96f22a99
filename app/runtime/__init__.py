"""The server's machinery: which thread does what (docs/architecture.md, "Threads").

- :mod:`~app.runtime.draw`: the session's draw queue: Bokeh models change only on the
  session's event loop, one draw after the other (:class:`~app.runtime.draw.DrawQueue`);
- :mod:`~app.runtime.bands`: scatter bands on threads of their own, one live band per
  session, sessions' chunks in turns, one computation shared by the sessions asking for it;
- :mod:`~app.runtime.offload`: heavy bands on a Dask cluster when one is configured;
- :mod:`~app.runtime.background`: work nobody waits for and work computed ahead, on a
  fixed number of threads of the process, superseded work dropped;
- :mod:`~app.runtime.shared_jobs`: long work sessions wait for (the belt waves of a tire),
  computed once for all of them on a thread of its own, each waiter told of its progress,
  its end or its failure, with a deadline and a retry of a lost run;
- :mod:`~app.runtime.uploads`: uploaded files read by parser processes side by side, off
  Panel's worker threads, bounded per session and in all; the pass of new models on a
  thread of its own;
- :mod:`~app.runtime.reports`: reports drawn one at a time in a process of their own while
  the click waits on the event loop;
- :mod:`~app.runtime.campaign_files`: the campaign result files of ``FBS_CAMPAIGN_DIR``,
  listed and opened (their case tables made by :mod:`app.results.campaign`), kept per
  process and read again only when a file changes;
- :mod:`~app.runtime.priority`: lower CPU priority of the threads that are not interactive;
- :mod:`~app.runtime.libraries`: what a page imports on first use, imported with the app
  (the server preloads it before its port opens);
- :mod:`~app.runtime.closed_pages`: a write to a page that has just closed is one log line;
- :mod:`~app.runtime.panel_private`: the only module of the app that touches Panel's private
  attributes (``tests/test_app_private_api.py`` scans every other one).

Everything the sessions compute is in :mod:`app.store` (what) and :mod:`app.results`
(how); nothing here computes a result.
"""
