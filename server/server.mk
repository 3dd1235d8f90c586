# server/server.mk - polydemd, the HTTP job service (included by the top Makefile).
DEB_PACKAGES += libmicrohttpd-dev libsqlite3-dev sqlite3 curl python3-yaml libjs-three

SERVER_SRC := $(wildcard server/*.c)
SERVER_OBJ := $(patsubst server/%.c,$(BUILD)/server/%.o,$(SERVER_SRC))
SERVER_LIBS := -lmicrohttpd -lsqlite3 -lpthread

$(BUILD)/server/%.o: server/%.c $(wildcard server/*.h) engine/polydem.h
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) -c $< -o $@

$(BUILD)/polydemd: $(SERVER_OBJ) $(BUILD)/libpolydem.a
	$(CC) $(SERVER_OBJ) $(BUILD)/libpolydem.a $(LDFLAGS) $(LDLIBS) $(SERVER_LIBS) -o $@

all: $(BUILD)/polydemd
check-build: $(BUILD)/polydemd

# clang-format for the server's sources, run by `make format` and `make format-check`
.PHONY: format-server format-check-server
format: format-server
format-check: format-check-server
format-server:
	clang-format -i server/*.c server/*.h
format-check-server:
	@clang-format --dry-run -Werror server/*.c server/*.h

# make install [PREFIX=/usr/local] [DESTDIR=]: the commands, the dashboard, the examples and the
# deployment files (deploy/README.md); polydemd finds <prefix>/share/polydem beside <prefix>/bin.
PREFIX ?= /usr/local
.PHONY: install
install: $(BUILD)/polydem $(BUILD)/polydemd
	install -d $(DESTDIR)$(PREFIX)/bin $(DESTDIR)$(PREFIX)/share/polydem/dashboard \
		$(DESTDIR)$(PREFIX)/share/polydem/examples $(DESTDIR)$(PREFIX)/share/polydem/deploy
	install -m 0755 $(BUILD)/polydem $(BUILD)/polydemd $(DESTDIR)$(PREFIX)/bin/
	cp -R clients/dashboard/. $(DESTDIR)$(PREFIX)/share/polydem/dashboard/
	install -m 0644 examples/*.json $(DESTDIR)$(PREFIX)/share/polydem/examples/
	install -m 0644 deploy/polydemd.service deploy/polydemd.conf.example deploy/README.md \
		$(DESTDIR)$(PREFIX)/share/polydem/deploy/
