package io.lumipose.app;

import com.sun.net.httpserver.HttpExchange;
import com.sun.net.httpserver.HttpHandler;
import com.sun.net.httpserver.HttpServer;

import java.io.ByteArrayOutputStream;
import java.io.IOException;
import java.io.InputStream;
import java.io.OutputStream;
import java.net.InetSocketAddress;
import java.nio.charset.StandardCharsets;
import java.util.ArrayList;
import java.util.Collections;
import java.util.LinkedHashMap;
import java.util.List;
import java.util.Map;

/**
 * A scripted server on 127.0.0.1 for the screens' tests: each "METHOD /path-prefix" answers the
 * given status and body (404 otherwise: no map, so no camera starts), and every request is kept.
 */
final class FakeServer implements AutoCloseable {
    static final class Request {
        final String method;
        final String uri;
        final byte[] body;

        Request(String method, String uri, byte[] body) {
            this.method = method;
            this.uri = uri;
            this.body = body;
        }

        String text() {
            return new String(body, StandardCharsets.UTF_8);
        }
    }

    private final HttpServer server;
    private final Map<String, String[]> answers = Collections.synchronizedMap(new LinkedHashMap<String, String[]>());
    final List<Request> requests = Collections.synchronizedList(new ArrayList<Request>());

    FakeServer() throws IOException {
        server = HttpServer.create(new InetSocketAddress("127.0.0.1", 0), 0);
        server.createContext("/", new HttpHandler() {
            @Override
            public void handle(HttpExchange x) throws IOException {
                byte[] body = read(x.getRequestBody());
                String uri = x.getRequestURI().toString();
                requests.add(new Request(x.getRequestMethod(), uri, body));
                String[] answer = {"404", "{\"error\": \"not_found\", \"field\": null, \"message\": \"no such route\"}"};
                synchronized (answers) {
                    for (Map.Entry<String, String[]> a : answers.entrySet()) {
                        if ((x.getRequestMethod() + " " + uri).startsWith(a.getKey())) {
                            answer = a.getValue();
                        }
                    }
                }
                byte[] out = answer[1].getBytes(StandardCharsets.UTF_8);
                x.getResponseHeaders().add("Content-Type", "application/json");
                x.sendResponseHeaders(Integer.parseInt(answer[0]), out.length);
                OutputStream o = x.getResponseBody();
                o.write(out);
                o.close();
            }
        });
        server.start();
    }

    String url() {
        return "http://127.0.0.1:" + server.getAddress().getPort();
    }

    FakeServer answer(String methodAndPathPrefix, int status, String body) {
        answers.put(methodAndPathPrefix, new String[] {String.valueOf(status), body});
        return this;
    }

    List<Request> requests(String methodAndPathPrefix) {
        List<Request> out = new ArrayList<Request>();
        synchronized (requests) {
            for (Request r : requests) {
                if ((r.method + " " + r.uri).startsWith(methodAndPathPrefix)) {
                    out.add(r);
                }
            }
        }
        return out;
    }

    private static byte[] read(InputStream in) throws IOException {
        ByteArrayOutputStream b = new ByteArrayOutputStream();
        byte[] buf = new byte[8192];
        for (int n; (n = in.read(buf)) > 0; ) {
            b.write(buf, 0, n);
        }
        return b.toByteArray();
    }

    @Override
    public void close() {
        server.stop(0);
    }
}
