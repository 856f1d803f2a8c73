"""`cogniframe studio`: edit a design in the browser (docs/studio.md).

    form.py     the form, generated from the params JSON Schema
    session.py  the state and the background work: validate and check each edit, the 3D view's
                parts through the build graph, the joints' FE, Save and Build
    app.py      the Starlette app: the page, its assets, the 3D scenes, the build's files, a WebSocket
    serve.py    `serve`: uvicorn on 127.0.0.1, the browser opened, Ctrl-C to stop
    static/     studio.js and studio.css (three.js and the viewer come from report/viewer/)
"""
