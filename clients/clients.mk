# clients/clients.mk - included by the top-level Makefile: the Debian packages the clients and
# their tests (tests/clients/, run by `make check`) need.
#   curl, jq          clients/sweep.sh and the test scripts
#   libjs-three       three.js for the dashboard's 3D viewer; polydemd serves
#                     /usr/share/javascript/three/ at /vendor/three/ (nothing is copied into the repo)
#   chromium          the dashboard's browser test, driven headless over the DevTools pipe
#                     (WebGL through SwiftShader, no GPU needed)
#   fonts-dejavu-core text in the headless browser's canvases
DEB_PACKAGES += curl jq libjs-three chromium fonts-dejavu-core
